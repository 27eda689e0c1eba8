// The Studies panel's messages between page and gateway: what
// lib/validate_pacs_message.js (through validate_message.js) lets through
// and refuses for 'pacs_endpoints', 'pacs_search', 'pacs_series',
// 'pacs_open', 'pacs_cancel' and 'export_dicom' (endpoint names, query
// values bounded in bytes, dates and ranges, modality codes, DICOM UIDs,
// pacs: sources, the export's description), without quoting a refused
// value; the page's search form as a message (public/pacs_query.js), the
// endpoint of a volume's source (public/pacs_source.js), and the words of
// the PACS errors (lib/explain_pacs_error.js).
// Usage: node --test pacs_messages.test.mjs
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const web = path.join(here, '../../client/web');
const load = (file) => import(pathToFileURL(path.join(web, file)).href);
const { parseMessage } = await load('lib/validate_message.js');
const { ProtoShape } = await load('lib/proto_shape.js');
const { explainPacsError } = await load('lib/explain_pacs_error.js');
const { GrpcStatus } = await load('lib/vpm_client.js');
const { searchMessage, dateRange, personName, shownDate } = await load('public/pacs_query.js');
const { pacsEndpointOf, parsePacsSource } = await load('public/pacs_source.js');
const { sourceWithStack } = await load('public/stack_picker.js');
const protoLoader = createRequire(path.join(web, 'package.json'))('@grpc/proto-loader');
const definition = protoLoader.loadSync(path.join(here, '../../proto/vpm/v3/vpm.proto'),
  { keepCase: true, longs: Number, enums: String, defaults: true, oneofs: true,
    includeDirs: [path.join(here, '../../proto')] });
const shape = new ProtoShape(definition);

const parse = (message) => parseMessage(shape, Buffer.from(JSON.stringify(message)), false);
const kStudy = '1.2.826.0.1.3680043.8.498.77010';
const kSeries = `${kStudy}.1`;
const kSource = `pacs:orthanc/${kStudy}/${kSeries}`;

test('PacsMessages_WellFormedOnesPass', () => {
  assert.deepEqual(parse({ type: 'pacs_endpoints' }), { type: 'pacs_endpoints' });
  assert.deepEqual(parse({ type: 'pacs_cancel' }), { type: 'pacs_cancel' });
  const search = { type: 'pacs_search', endpoint: 'orthanc', patient_name: 'DOE^J*',
                   patient_id: 'PID-42', patient_birth_date: '19700101',
                   study_date: '20240101-20241231', modality: 'CT', accession_number: 'ACC 1',
                   limit: 1000 };
  assert.deepEqual(parse(search), search);
  assert.deepEqual(parse({ type: 'pacs_search', endpoint: 'cloud.eu_1-b' }).endpoint, 'cloud.eu_1-b');
  for (const studyDate of ['20240101', '20240101-', '-20241231', '', undefined]) {
    assert.equal(parse({ type: 'pacs_search', endpoint: 'o', study_date: studyDate }).study_date,
                 studyDate);
  }
  assert.equal(parse({ type: 'pacs_search', endpoint: 'o', patient_name: 'É'.repeat(32) })
    .patient_name.length, 32);
  assert.equal(parse({ type: 'pacs_series', endpoint: 'orthanc', study_uid: kStudy }).study_uid, kStudy);
  assert.equal(parse({ type: 'pacs_open', source: kSource }).source, kSource);
  assert.deepEqual(parse({ type: 'export_dicom', endpoint: 'orthanc' }),
                   { type: 'export_dicom', endpoint: 'orthanc' });
  assert.equal(parse({ type: 'export_dicom', endpoint: 'orthanc', series_description: 'x'.repeat(64) })
    .series_description.length, 64);
});

test('PacsMessages_BadEndpointsAreRefused', () => {
  for (const endpoint of [undefined, null, 7, '', '.hidden', 'a/b', 'a b', 'x'.repeat(65), 'ü',
                          ['orthanc'], 'orthanc\n']) {
    for (const message of [{ type: 'pacs_search' }, { type: 'pacs_series', study_uid: kStudy },
                           { type: 'export_dicom' }]) {
      assert.throws(() => parse({ ...message, endpoint }), /endpoint: a PACS endpoint name/,
                    `${message.type} ${JSON.stringify(endpoint)}`);
    }
  }
});

test('PacsMessages_QueryValuesAreBoundedAndNeverQuoted', () => {
  const secret = 'SECRET^PATIENT';
  const refused = (fields, expect) => {
    let error = null;
    try {
      parse({ type: 'pacs_search', endpoint: 'orthanc', ...fields });
    } catch (e) {
      error = e;
    }
    assert.ok(error, `${JSON.stringify(fields)} passed`);
    assert.match(error.message, expect, JSON.stringify(fields));
    assert.ok(!error.message.includes('SECRET'), `the error quotes the value: ${error.message}`);
  };
  for (const key of ['patient_name', 'patient_id', 'accession_number']) {
    refused({ [key]: `${secret}${'x'.repeat(64)}` }, new RegExp(`${key}: a string of at most 64 bytes`));
    refused({ [key]: `${secret}\n` }, new RegExp(`${key}: .*without control characters`));
    refused({ [key]: 42 }, new RegExp(`${key}: a string`));
  }
  refused({ patient_name: `${secret}${'é'.repeat(26)}` }, /patient_name: a string of at most 64 bytes/);
  for (const key of ['study_date', 'patient_birth_date']) {
    for (const v of ['2024', '2024-01-01', '20240101-20241231-', '-', 'SECRET01', '20240101--']) {
      refused({ [key]: v }, new RegExp(`${key}: YYYYMMDD, or a range`));
    }
  }
  for (const modality of ['C T', 'CT;', 'x'.repeat(17), 'SECRET-1']) {
    refused({ modality }, /modality: a modality code/);
  }
  for (const limit of [0, 1001, 1.5, '10', null, -1]) refused({ limit }, /limit: an integer from 1 to 1000/);
  refused({ patient_nam: secret }, /pacs_search: no field 'patient_nam'/);
});

test('PacsMessages_UidsAndSourcesAreChecked', () => {
  for (const studyUid of [undefined, '', '1..2', '.1', '1.', '1.2a', `1.${'2'.repeat(63)}`, 7,
                          '../1', '1.2/3']) {
    assert.throws(() => parse({ type: 'pacs_series', endpoint: 'orthanc', study_uid: studyUid }),
                  /study_uid: a DICOM UID/, JSON.stringify(studyUid));
  }
  for (const source of [undefined, '', 'phantom:abdomen', 'pacs:orthanc', `pacs:orthanc/${kStudy}`,
                        `pacs:orthanc/${kStudy}/${kSeries}/x`, `pacs:.x/${kStudy}/${kSeries}`,
                        `pacs:orthanc/${kStudy}/../${kSeries}`, `pacs:orthanc/${kStudy}/1.2a`,
                        `PACS:orthanc/${kStudy}/${kSeries}`, 5]) {
    assert.throws(() => parse({ type: 'pacs_open', source }), /source: pacs:ENDPOINT\/STUDY_UID\/SERIES_UID/,
                  JSON.stringify(source));
  }
  for (const d of ['x'.repeat(65), 'a\nb', 3, null]) {
    assert.throws(() => parse({ type: 'export_dicom', endpoint: 'orthanc', series_description: d }),
                  /series_description: a string of at most 64/, JSON.stringify(d));
  }
  assert.throws(() => parse({ type: 'pacs_everything' }), /unknown message type 'pacs_everything'/);
});

test('PacsSource_NamesTheEndpointOfAPacsSeriesOnly', () => {
  assert.deepEqual(parsePacsSource(kSource),
                   { endpoint: 'orthanc', studyUid: kStudy, seriesUid: kSeries, stack: 0 });
  assert.deepEqual(parsePacsSource(`${kSource}?stack=2`),
                   { endpoint: 'orthanc', studyUid: kStudy, seriesUid: kSeries, stack: 2 });
  assert.equal(pacsEndpointOf(`pacs:cloud-1/${kStudy}/${kSeries}`), 'cloud-1');
  for (const source of ['phantom:abdomen', 'upload:abc', 'ct.nii.gz', 'pacs:orthanc', '', null,
                        undefined, `pacs:/${kStudy}/${kSeries}`, `${kSource}?stack=0`,
                        `${kSource}?stack=`, `${kSource}?series=2`, `${kSource}?stack=2?stack=3`,
                        `${kSource}?stack=100001`, `${kSource}?stack=2&stack=3`]) {
    assert.equal(pacsEndpointOf(source), null, JSON.stringify(source));
  }
});

test('PacsQuery_TheSearchFormBecomesAMessageTheGatewayAccepts', () => {
  const m = searchMessage('orthanc', { patient_name: ' DOE^J* ', patient_id: '', birth_date: '1970-01-01',
                                       study_date_from: '2024-01-01', study_date_to: '2024-12-31',
                                       modality: 'ct', accession_number: '', limit: '50' });
  assert.deepEqual(m, { type: 'pacs_search', endpoint: 'orthanc', patient_name: 'DOE^J*',
                        patient_birth_date: '19700101', study_date: '20240101-20241231',
                        modality: 'CT', limit: 50 });
  assert.deepEqual(parse(m), m);
  assert.deepEqual(searchMessage('o', {}), { type: 'pacs_search', endpoint: 'o' });
  assert.equal(dateRange('2024-01-01', '', 'd'), '20240101-');
  assert.equal(dateRange('', '20241231', 'd'), '-20241231');
  assert.equal(dateRange('20240315', '2024-03-15', 'd'), '20240315');
  assert.throws(() => dateRange('20241231', '20240101', 'study date'), /study date: the first date is after/);
  assert.throws(() => searchMessage('', {}), /pick a PACS endpoint/);
  assert.throws(() => searchMessage('o', { birth_date: '1/1/1970' }), /birth date: a date/);
  assert.throws(() => searchMessage('o', { modality: 'C T' }), /modality: a DICOM modality code/);
  assert.throws(() => searchMessage('o', { patient_name: 'x'.repeat(65) }), /patient name: at most 64 bytes/);
  assert.throws(() => searchMessage('o', { limit: '0' }), /limit: 1 to 1000/);
  assert.equal(personName('DOE^JOHN^Q'), 'DOE, JOHN Q');
  assert.equal(personName('DOE'), 'DOE');
  assert.equal(personName('Yamada^Tarou=山田^太郎'), 'Yamada, Tarou');
  assert.equal(shownDate('20240315'), '2024-03-15');
  assert.equal(shownDate(''), '');
});

test('PacsErrors_SayWhatToDo', () => {
  const explain = (code, details) => explainPacsError({ code, details }, 'Searching orthanc', '127.0.0.1:1');
  assert.match(explain(GrpcStatus.PERMISSION_DENIED, "no PACS endpoint 'orthanc' that you may use"),
               /^Searching orthanc: not allowed: no PACS endpoint 'orthanc' that you may use\. Ask/);
  assert.match(explain(GrpcStatus.UNAVAILABLE, "PACS 'orthanc': connection refused"),
               /the PACS is not reachable \(PACS 'orthanc': connection refused\)\. vpm-server is up/);
  assert.match(explain(GrpcStatus.INVALID_ARGUMENT, 'series 1.2 holds no images'),
               /^Searching orthanc: series 1\.2 holds no images$/);
  assert.match(explain(GrpcStatus.RESOURCE_EXHAUSTED, 'over the budget'), /too large for the server/);
  assert.match(explain(GrpcStatus.FAILED_PRECONDITION, 'this server has no PACS endpoints'),
               /this server has no PACS \(started without --pacs\)\./);
  assert.match(explain(GrpcStatus.UNIMPLEMENTED, 'unknown method'), /an older version/);
  assert.ok(explain(GrpcStatus.NOT_FOUND, 'x'.repeat(5000)).length < 700);
});

test('ThumbnailAndDataRootMessages_CheckedBeforeTheServer', () => {
  const thumb = { type: 'pacs_thumbnail', endpoint: 'orthanc', study_uid: kStudy, series_uid: kSeries };
  assert.deepEqual(parse(thumb), thumb);
  for (const [fields, why] of [[{ series_uid: '1.2a' }, /series_uid: a DICOM UID/],
                               [{ study_uid: '' }, /study_uid: a DICOM UID/],
                               [{ endpoint: '../x' }, /endpoint: a PACS endpoint name/],
                               [{ size_px: 4096 }, /pacs_thumbnail: no field 'size_px'/]]) {
    assert.throws(() => parse({ ...thumb, ...fields }), why);
  }
  assert.deepEqual(parse({ type: 'data_ls', path: '' }), { type: 'data_ls', path: '' });
  assert.equal(parse({ type: 'data_ls', path: 'cases/ct' }).path, 'cases/ct');
  for (const path of [undefined, 7, '/etc', '..', 'a/../b', 'a\nb', 'x'.repeat(4097)]) {
    assert.throws(() => parse({ type: 'data_ls', path }), /path: a folder relative to the data root/,
                  String(path).slice(0, 20));
  }
  assert.throws(() => parse({ type: 'data_ls', path: '', depth: 3 }), /data_ls: no field 'depth'/);
});

test('UsersFile_TakesTheBrowsePermission', async () => {
  const { parseUsersFile } = await load('lib/users.js');
  const hash = 'a'.repeat(64);
  assert.deepEqual(parseUsersFile(`alice ${hash} browse-data-root\n`, 'u').map((u) => u.name),
                   ['alice']);
  assert.throws(() => parseUsersFile(`alice ${hash} root\n`, 'u'), /unknown permission 'root'/);
  assert.throws(() => parseUsersFile('alice\n', 'u'), /1 fields, not 2/);
});

test('StackSources_SetTheStackAndKeepTheRest', () => {
  assert.equal(sourceWithStack(kSource, 2), `${kSource}?stack=2`);
  assert.equal(sourceWithStack(`${kSource}?stack=2`, 1), `${kSource}?stack=1`);
  // A PACS source with a stack passes the gateway's check.
  assert.equal(parse({ type: 'pacs_open', source: sourceWithStack(kSource, 3) }).source,
               `${kSource}?stack=3`);
  assert.equal(sourceWithStack('mr/t1', 2), 'mr/t1?stack=2');
  assert.equal(sourceWithStack('mr/t1?series=3&spacing=1', 2), 'mr/t1?series=3&spacing=1&stack=2');
  assert.equal(sourceWithStack('mr/t1?stack=2&series=3', 1), 'mr/t1?series=3&stack=1');
});
