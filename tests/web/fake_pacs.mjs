// The PACS calls of the stand-in vpm-server (fake_vpm_server.mjs), for the
// gateway's tests: ListPacsEndpoints, SearchStudies, ListSeries, LoadVolume
// of pacs: sources with GetLoadProgress, and ExportDicom, answering as
// docs/PACS.md says vpm-server does.
//
// Endpoints come from setPacs([{name, users: ['alice' | '*'], down}]).
// No endpoints (the default) is a server without --pacs: the calls answer
// FAILED_PRECONDITION "this server has no PACS endpoints" and
// ListPacsEndpoints an empty list; `older = true` answers ListPacsEndpoints
// UNIMPLEMENTED, as a server older than that call does. An endpoint the
// caller may not use, or that does not exist, is PERMISSION_DENIED; a
// `down` one UNAVAILABLE. Every endpoint holds kStudies: DOE^JOHN's CT
// study with a CT series (it loads in steps: retrieving, reading,
// uploading, done, one a GetLoadProgress of its progress id), a dose report
// (INVALID_ARGUMENT "holds no images" once retrieving) and a series too
// large for the cache (RESOURCE_EXHAUSTED); ROE^JANE's MR study.
// ExportDicom streams warping, writing and sending, then the summary; a
// series_description of 'with files' also streams one file part (which the
// gateway must drop).
export const kStudyUid = '1.2.826.0.1.3680043.8.498.1';
export const kCtSeriesUid = `${kStudyUid}.1`;
export const kSrSeriesUid = `${kStudyUid}.2`;
export const kHugeSeriesUid = `${kStudyUid}.3`;
export const kStudies = [
  { study_uid: kStudyUid, patient_name: 'DOE^JOHN', patient_id: 'PID-DOE-4242',
    patient_birth_date: '19700101', study_date: '20240315', study_description: 'CT abdomen',
    accession_number: 'ACC-1', modalities: ['CT', 'SR'], series_count: 3, instance_count: 5113,
    series: [
      { series_uid: kCtSeriesUid, modality: 'CT', description: 'Abdomen 1.0', body_part: 'ABDOMEN',
        series_number: 2, instance_count: 112 },
      { series_uid: kSrSeriesUid, modality: 'SR', description: 'Dose report', body_part: '',
        series_number: 999, instance_count: 1 },
      { series_uid: kHugeSeriesUid, modality: 'CT', description: 'Thin slices', body_part: 'ABDOMEN',
        series_number: 3, instance_count: 5000 }] },
  { study_uid: '1.2.826.0.1.3680043.8.498.2', patient_name: 'ROE^JANE', patient_id: 'PID-ROE-7777',
    patient_birth_date: '19800202', study_date: '20231201', study_description: 'MR liver',
    accession_number: 'ACC-2', modalities: ['MR'], series_count: 1, instance_count: 40,
    series: [{ series_uid: '1.2.826.0.1.3680043.8.498.2.1', modality: 'MR', description: 'T1',
               body_part: 'LIVER', series_number: 1, instance_count: 40 }] },
];
const kStepMs = 30;

// DICOM wildcards ('*', '?') as a RegExp over the whole value.
function wildcard(pattern) {
  const escaped = pattern.replace(/[.+^${}()|[\]\\]/g, '\\$&');
  return new RegExp(`^${escaped.replaceAll('*', '.*').replaceAll('?', '.')}$`, 'i');
}

function inRange(date, range) {
  const [from, to = from] = range.includes('-') ? range.split('-') : [range, range];
  return (!from || date >= from) && (!to || date <= to);
}

// users: {token: name}; sourceOfSession(id, authorization): the source of
// the session's volume when the caller owns it, else null.
const kOnePixelPng =
  'iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAAAAAA6fptVAAAACklEQVR4nGNgAAAAAgABSK+kcQAAAABJRU5ErkJggg==';

export function makePacs(grpc, users, sourceOfSession) {
  const state = { endpoints: [], progress: new Map(), advance: new Map(), cancelledLoads: 0 };
  const refuse = (code, details) => Object.assign(new Error(details), { code, details });
  const userOf = (call) => users[String(call.metadata.get('authorization')[0] ?? '')
    .replace(/^Bearer /, '')] ?? 'default';
  const endpointFor = (call, name) => {
    if (!state.endpoints.length) {
      throw refuse(grpc.status.FAILED_PRECONDITION, 'this server has no PACS endpoints');
    }
    const e = state.endpoints.find((x) => x.name === name);
    if (!e || !(e.users.includes('*') || e.users.includes(userOf(call)))) {
      throw refuse(grpc.status.PERMISSION_DENIED, `no PACS endpoint '${name}' that you may use`);
    }
    if (e.down) {
      throw refuse(grpc.status.UNAVAILABLE,
                   `PACS '${name}': GET /dicom-web/studies: Could not connect to server`);
    }
    return e;
  };
  const search = (r) => {
    const matches = kStudies.filter((s) =>
      (!r.patient_name || wildcard(r.patient_name).test(s.patient_name)) &&
      (!r.patient_id || r.patient_id === s.patient_id) &&
      (!r.study_date || inRange(s.study_date, r.study_date)) &&
      (!r.modality || s.modalities.includes(r.modality)));
    const limit = r.limit || 100;
    return { studies: matches.slice(0, limit).map(({ series, ...s }) => s),
             truncated: matches.length > limit };
  };
  const setProgress = (id, stage, fraction, extra = {}) => {
    if (id) state.progress.set(id, { stage, fraction, done: false, error_code: 0, ...extra });
  };

  // LoadVolume of a pacs: source: answers through `callback` with
  // makeVolume(source) once the steps are done.
  state.load = (call, callback, makeVolume) => {
    const { source, progress_id: id } = call.request;
    const [endpoint, studyUid, seriesUid] = source.slice('pacs:'.length).split('/');
    try {
      endpointFor(call, endpoint);
    } catch (e) {
      callback(e);
      return;
    }
    const series = kStudies.find((s) => s.study_uid === studyUid)?.series
      .find((s) => s.series_uid === seriesUid);
    const fail = (code, details) => {
      setProgress(id, 'failed', 0, { done: true, error_code: code, error_message: details });
      callback(refuse(code, details));
    };
    if (!series) return fail(grpc.status.NOT_FOUND, `series ${seriesUid} not found on '${endpoint}'`);
    if (series.instance_count > 1000) {
      return fail(grpc.status.RESOURCE_EXHAUSTED,
                  `series ${seriesUid} is larger than the PACS cache's budget`);
    }
    // Polled: one step a GetLoadProgress (the test sees each stage); else a
    // step every kStepMs.
    const steps = [['retrieving', 0.2], ['retrieving', 0.6], ['reading', 0.8], ['uploading', 0.95]];
    let i = 0;
    let timer = null;
    const advance = () => {
      if (i < steps.length) {
        setProgress(id, ...steps[i++]);
        if (series.modality === 'SR' && i === 2) {
          stop();
          fail(grpc.status.INVALID_ARGUMENT, `series ${seriesUid} holds no images`);
        }
        return;
      }
      stop();
      setProgress(id, 'done', 1, { done: true });
      setTimeout(() => callback(null, makeVolume(source)), kStepMs);
    };
    const stop = () => {
      clearInterval(timer);
      state.advance.delete(id);
    };
    setProgress(id, 'queued', 0);
    if (id) state.advance.set(id, advance);
    else timer = setInterval(advance, kStepMs);
    call.on('cancelled', () => {
      stop();
      state.cancelledLoads += 1;
    });
    return undefined;
  };

  state.handlers = (unary) => ({
    ListPacsEndpoints: unary('ListPacsEndpoints', (r, call) => {
      if (state.older) throw refuse(grpc.status.UNIMPLEMENTED, 'unknown method ListPacsEndpoints');
      return { endpoints: state.endpoints.filter((e) => e.users.includes('*') || e.users.includes(userOf(call)))
        .map((e) => e.name) };
    }),
    SearchStudies: unary('SearchStudies', (r, call) => {
      endpointFor(call, r.endpoint);
      return search(r);
    }),
    ListSeries: unary('ListSeries', (r, call) => {
      endpointFor(call, r.endpoint);
      const study = kStudies.find((s) => s.study_uid === r.study_uid);
      if (!study) throw refuse(grpc.status.NOT_FOUND, `study ${r.study_uid} not found`);
      return { series: study.series.map((s) => ({
        ...s, source: `pacs:${r.endpoint}/${study.study_uid}/${s.series_uid}` })) };
    }),
    // A 1 x 1 grey PNG for an image series; a series without images refused
    // as vpm-server refuses it.
    GetSeriesThumbnail: unary('GetSeriesThumbnail', (r, call) => {
      endpointFor(call, r.endpoint);
      const series = kStudies.find((s) => s.study_uid === r.study_uid)?.series
        .find((s) => s.series_uid === r.series_uid);
      if (!series) throw refuse(grpc.status.NOT_FOUND, `series ${r.series_uid} not found`);
      if (series.modality === 'SR') {
        throw refuse(grpc.status.INVALID_ARGUMENT, `series ${r.series_uid}: the series holds no image`);
      }
      return { png: Buffer.from(kOnePixelPng, 'base64'), width: 1, height: 1 };
    }),
    // The data root (not the PACS's, but the same stand-in): alice may
    // browse it, nobody else.
    ListDataRoot: unary('ListDataRoot', (r, call) => {
      if (userOf(call) !== 'alice') {
        throw refuse(grpc.status.PERMISSION_DENIED, 'you may not browse the server\'s files');
      }
      if (r.path === 'missing') throw refuse(grpc.status.NOT_FOUND, "source: 'missing' is not in the data root");
      return { path: r.path, truncated: false, entries: [
        { name: 'ct', kind: 'DICOM_FOLDER', size_bytes: 0, modified_unix_ms: 1700000000000,
          source: r.path ? `${r.path}/ct` : 'ct' },
        { name: 'kidney.nii.gz', kind: 'VOLUME_FILE', size_bytes: 123456,
          modified_unix_ms: 1700000000000, source: r.path ? `${r.path}/kidney.nii.gz` : 'kidney.nii.gz' }] };
    }),
    GetLoadProgress: unary('GetLoadProgress', (r) => {
      state.advance.get(r.progress_id)?.();
      const p = state.progress.get(r.progress_id);
      if (!p) throw refuse(grpc.status.NOT_FOUND, `no load '${r.progress_id}'`);
      return p;
    }),
    ExportDicom: (call) => exportDicom(call),
  });

  function exportDicom(call) {
    const r = call.request;
    state.record('ExportDicom', call);
    let source;
    try {
      endpointFor(call, r.endpoint);
      source = sourceOfSession(r.session_id, call.metadata.get('authorization')[0] ?? null);
      if (!source) throw refuse(grpc.status.NOT_FOUND, `no session '${r.session_id}'`);
    } catch (e) {
      call.emit('error', e);
      return;
    }
    const studyUid = source.startsWith('pacs:') ? source.split('/')[1] : '2.25.1234';
    const parts = [{ stage: 'warping', fraction: 0.1 }, { stage: 'writing', fraction: 0.5 }];
    if (r.series_description === 'with files') {
      parts.push({ file_name: 'derived/000001.dcm', data: Buffer.alloc(4096, 7) });
    }
    parts.push({ stage: 'sending', fraction: 0.9 });
    parts.push({ summary: {
      study_uid: studyUid, derived_series_uid: '2.25.100', capture_series_uid: '2.25.101',
      instances: 113, endpoint: r.endpoint,
      series_description: r.series_description || 'vpm deformed: grab', max_displacement_mm: 1.5,
      bytes: 4 * 1024 * 1024 } });
    let i = 0;
    const timer = setInterval(() => {
      if (i < parts.length) {
        call.write(parts[i++]);
        return;
      }
      clearInterval(timer);
      call.end();
    }, kStepMs);
    call.on('cancelled', () => clearInterval(timer));
  }

  return state;
}
