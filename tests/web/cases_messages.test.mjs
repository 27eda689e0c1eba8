// The case messages between page and gateway: what lib/validate_message.js
// lets through and refuses for 'cases', 'open_case', 'rename_case',
// 'delete_case' and 'undo' (ids, bounded titles, booleans, the camera and
// settings checked against the proto, the page's sequence an open carries),
// and the page's undo keys
// (public/undo_keys.js: Ctrl/Cmd+Z, Ctrl/Cmd+Shift+Z, Ctrl+Y; text fields
// keep their own).
// Usage: node --test cases_messages.test.mjs
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const web = path.join(here, '../../client/web');
const load = (file) => import(pathToFileURL(path.join(web, file)).href);
const { parseMessage, kMaxCaseTitleBytes } = await load('lib/validate_message.js');
const { ProtoShape } = await load('lib/proto_shape.js');
const { undoKey } = await load('public/undo_keys.js');
const { takesTyping } = await load('public/typing_target.js');
const protoLoader = createRequire(path.join(web, 'package.json'))('@grpc/proto-loader');
const definition = protoLoader.loadSync(path.join(here, '../../proto/vpm/v3/vpm.proto'),
  { keepCase: true, longs: Number, enums: String, defaults: true, oneofs: true,
    includeDirs: [path.join(here, '../../proto')] });
const shape = new ProtoShape(definition);

const parse = (message) => parseMessage(shape, Buffer.from(JSON.stringify(message)), false);
const kId = 'case-0123456789abcdef0123456789abcdef';

test('CaseMessages_WellFormedOnesPass', () => {
  assert.deepEqual(parse({ type: 'cases' }), { type: 'cases' });
  const open = { type: 'open_case', case_id: kId, settings: { mode: 'dvr', width: 256, height: 256 },
                 camera: { azimuth_deg: 30, elevation_deg: -10, distance_mm: 400,
                           pan_mm: { x: 1, y: 2, z: 3 } } };
  assert.deepEqual(parse(open), open);
  assert.equal(parse({ type: 'open_case', case_id: kId, camera: null }).case_id, kId);
  assert.equal(parse({ type: 'rename_case', case_id: kId, title: 'Liver, left lobe (Ü)' }).title,
               'Liver, left lobe (Ü)');
  assert.equal(parse({ type: 'rename_case', case_id: kId, title: 'x'.repeat(kMaxCaseTitleBytes) })
    .title.length, kMaxCaseTitleBytes);
  assert.equal(parse({ type: 'delete_case', case_id: kId }).case_id, kId);
  assert.equal(parse({ type: 'undo' }).redo, undefined);
  assert.equal(parse({ type: 'undo', redo: true }).redo, true);
});

test('CaseMessages_BadIdsAreRefused', () => {
  for (const type of ['open_case', 'rename_case', 'delete_case']) {
    for (const caseId of [undefined, null, 7, '', 'x'.repeat(129), '../cases.sqlite', 'case 1',
                          'case-1\n', '-case', { id: kId }, [kId]]) {
      assert.throws(() => parse({ type, case_id: caseId, title: 'T' }), /case_id: a case id/,
                    `${type} ${JSON.stringify(caseId)}`);
    }
  }
  assert.equal(parse({ type: 'delete_case', case_id: 'x'.repeat(128) }).case_id.length, 128);
});

test('CaseMessages_TitlesAreBoundedInBytesAndPrintable', () => {
  const rename = (title) => parse({ type: 'rename_case', case_id: kId, title });
  for (const title of [undefined, null, 5, '', '   ', 'x'.repeat(kMaxCaseTitleBytes + 1),
                       'é'.repeat(kMaxCaseTitleBytes / 2 + 1), 'a\nb', 'tab\there', 'nul\u0000',
                       'del\u007f', ['T']]) {
    assert.throws(() => rename(title), /title: a string of 1 to 256 bytes/, JSON.stringify(title));
  }
  assert.equal(rename('é'.repeat(kMaxCaseTitleBytes / 2)).title.length, kMaxCaseTitleBytes / 2);
});

test('CaseMessages_UndoCameraAndSettingsAreChecked', () => {
  for (const redo of ['true', 1, null, {}]) {
    assert.throws(() => parse({ type: 'undo', redo }), /redo: true or false/);
  }
  assert.throws(() => parse({ type: 'open_case', case_id: kId, camera: { nope: 1 } }),
                /camera: .*no field 'nope'/);
  assert.throws(() => parse({ type: 'open_case', case_id: kId, camera: { azimuth_deg: 'x' } }),
                /camera\.azimuth_deg: a finite number/);
  assert.throws(() => parse({ type: 'open_case', case_id: kId, settings: { mode: 'x' } }),
                /settings\.mode: one of/);
  assert.throws(() => parse({ type: 'open_case', case_id: kId, settings: [] }), /settings: an object/);
  assert.throws(() => parse({ type: 'cases_all' }), /unknown message type 'cases_all'/);
  assert.equal(parse({ type: 'open_case', case_id: kId, sequence: 12 }).sequence, 12);
  for (const sequence of [-1, 1.5, '3', null, 2 ** 53]) {
    assert.throws(() => parse({ type: 'open_case', case_id: kId, sequence }), /sequence: an integer/);
    assert.throws(() => parse({ type: 'open', source: 'phantom:abdomen', sequence }),
                  /sequence: an integer/);
  }
});

test('UndoKeys_CtrlOrCmdZUndoesWithShiftRedoes', () => {
  assert.equal(undoKey({ key: 'z', ctrlKey: true }), 'undo');
  assert.equal(undoKey({ key: 'z', metaKey: true }), 'undo');  // macOS
  assert.equal(undoKey({ key: 'Z', ctrlKey: true, shiftKey: true }), 'redo');
  assert.equal(undoKey({ key: 'Z', metaKey: true, shiftKey: true }), 'redo');
  assert.equal(undoKey({ key: 'y', ctrlKey: true }), 'redo');
  assert.equal(undoKey({ key: 'я', code: 'KeyZ', ctrlKey: true }), 'undo');  // another layout
  assert.equal(undoKey({ key: 'z' }), null);
  assert.equal(undoKey({ key: 'z', ctrlKey: true, altKey: true }), null);
  assert.equal(undoKey({ key: 'x', ctrlKey: true }), null);
  assert.equal(undoKey({ key: 'y', metaKey: true }), null);  // Cmd+Y is the browser's history
});

test('UndoKeys_TextFieldsKeepTheirOwnUndo', () => {
  assert.ok(takesTyping({ tagName: 'INPUT', type: 'number' }));
  assert.ok(takesTyping({ tagName: 'input', type: 'text' }));
  assert.ok(takesTyping({ tagName: 'TEXTAREA' }));
  assert.ok(takesTyping({ tagName: 'DIV', isContentEditable: true }));
  assert.ok(!takesTyping({ tagName: 'INPUT', type: 'checkbox' }));
  assert.ok(!takesTyping({ tagName: 'INPUT', type: 'range' }));
  assert.ok(!takesTyping({ tagName: 'CANVAS' }));
  assert.ok(!takesTyping({ tagName: 'BODY' }));
  assert.ok(!takesTyping(null));
});
