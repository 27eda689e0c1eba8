// The upload panel's status line (public/upload_panel.js) never goes back a
// stage: the browser may report the body sent (xhr.upload progress and
// load) after the gateway has already said that it passes the file on or
// that vpm-server reads it (serverProgress), and that later stage stays
// shown. Before the gateway speaks, the browser's own progress is shown.
// Usage: node --test upload_panel.test.mjs
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
// The page's globals the panel touches: drops on the document, one request.
globalThis.document = { addEventListener() {} };
class FakeXhr {
  constructor() {
    this.upload = {};
    FakeXhr.last = this;
  }
  open() {}
  setRequestHeader() {}
  send() {}
}
globalThis.XMLHttpRequest = FakeXhr;
const { UploadPanel } = await import(
  pathToFileURL(path.join(here, '../../client/web/public/upload_panel.js')).href);

function element() {
  return { hidden: false, dataset: {}, value: 0, addEventListener() {}, removeAttribute() {} };
}

// A panel on fake elements, uploading `name`; said: the message lines.
function sending(name) {
  const elements = new Map();
  const $ = (id) => {
    if (!elements.has(id)) elements.set(id, element());
    return elements.get(id);
  };
  const said = [];
  const panel = new UploadPanel({ $, say: (text) => said.push(text), openVolume() {} });
  panel.running = { name, packing: null, xhr: null };
  panel.send(new Blob([new Uint8Array(2048)]), name);
  return { panel, said, xhr: FakeXhr.last };
}

test('the body reported sent after the gateway moved on leaves the later stage shown', () => {
  const { panel, said, xhr } = sending('ct.nii');
  panel.serverProgress({ stage: 'reading', bytes: 2048, total_bytes: 2048 });
  assert.equal(said.at(-1), 'ct.nii: reading on the server ...');
  xhr.upload.onprogress({ loaded: 2048, total: 2048 });
  xhr.upload.onload();
  assert.equal(said.at(-1), 'ct.nii: reading on the server ...');
  assert.equal(panel.root.dataset.state, 'reading');
});

test('the gateway passing the file on is not undone by the browser either', () => {
  const { panel, said, xhr } = sending('ct.nii');
  panel.serverProgress({ stage: 'sending', bytes: 1024, total_bytes: 2048 });
  const passing = said.at(-1);
  assert.match(passing, /^ct\.nii: the gateway is passing it to vpm-server/);
  xhr.upload.onload();
  assert.equal(said.at(-1), passing);
});

test('before the gateway speaks, the browser\'s progress and end are shown', () => {
  const { panel, said, xhr } = sending('ct.nii');
  xhr.upload.onprogress({ loaded: 1024, total: 2048 });
  assert.match(said.at(-1), /^Uploading ct\.nii: 1(\.0)? KiB of 2(\.0)? KiB sent \.\.\.$/);
  xhr.upload.onload();
  assert.equal(said.at(-1), 'Uploaded ct.nii; the gateway passes it to vpm-server ...');
  assert.equal(panel.root.dataset.state, 'reading');
  panel.serverProgress({ stage: 'reading', bytes: 2048, total_bytes: 2048 });
  assert.equal(said.at(-1), 'ct.nii: reading on the server ...');
});
