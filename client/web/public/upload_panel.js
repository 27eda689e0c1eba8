// Uploads from the desktop (docs/WEB.md, "Uploads"): the Upload... and
// Folder... buttons of the volume row, and files or a folder dropped
// anywhere on the page. What is sent is upload_files.js's decision: one
// NIfTI, NRRD or MetaImage file or one archive as is, DICOM files packed
// here into a stored ZIP (zip_writer.js). The bytes go by POST /upload to
// the gateway (lib/volume_upload.js), naming this tab (hello.tab_id), which
// passes them to vpm-server's UploadVolume; the page then opens the new
// volume as one picked from the volume list (`openVolume`, app.js). Files
// over the gateway's cap (hello.max_upload_bytes) are refused here, before
// anything is read or sent.
//
// Element ids (stable: end-to-end tests drive the upload through them):
//   #upload               the volume row's part; data-state: idle | packing |
//                         sending | reading | opening | opened | error | cancelled
//   #upload-file          picks files (#upload-input, multiple)
//   #upload-folder        picks a folder (#upload-folder-input, webkitdirectory)
//   #upload-progress      <progress> of the stage under way (no value: the
//                         server is reading)
//   #upload-cancel        stops packing or sending
//   #upload-drop          the overlay shown while files are dragged over the page
import { planUpload, sizeText } from './upload_files.js';
import { kMaxZipEntries, storeZip } from './zip_writer.js';

const kMaxWalkedFiles = kMaxZipEntries + 1;  // a dropped folder is walked this far at most

// The files under dropped entries (FileSystemEntry), as [{file, path}];
// hidden files and folders are not walked.
async function walk(entries) {
  const out = [];
  const visit = async (entry, prefix) => {
    if (out.length >= kMaxWalkedFiles || entry.name.startsWith('.')) return;
    const path = `${prefix}${entry.name}`;
    if (entry.isFile) {
      out.push({ file: await new Promise((resolve, reject) => entry.file(resolve, reject)), path });
      return;
    }
    if (!entry.isDirectory) return;
    const reader = entry.createReader();
    for (;;) {  // readEntries answers in batches until an empty one
      const batch = await new Promise((resolve, reject) => reader.readEntries(resolve, reject));
      if (!batch.length) return;
      for (const child of batch) await visit(child, `${path}/`);
    }
  };
  for (const entry of entries) await visit(entry, '');
  return out;
}

export class UploadPanel {
  // $: id -> element; say(text, kind): the page's message line;
  // openVolume(volume): opens an uploaded VolumeInfo as the volume list does.
  constructor({ $, say, openVolume }) {
    Object.assign(this, { $, say, openVolume });
    this.root = $('upload');
    this.tabId = null;       // this tab's id at the gateway (hello), null while away
    this.maxBytes = 0;
    this.running = null;     // {name, packing: AbortController, xhr, gatewayStage}
    this.opening = null;     // the volume id uploaded and being opened
    this.lastVolume = null;  // the VolumeInfo of the last upload (for tests)
    this.lastError = null;   // {code, message} of the last upload's failure (for tests)
    $('upload-file').addEventListener('click', () => $('upload-input').click());
    $('upload-folder').addEventListener('click', () => $('upload-folder-input').click());
    for (const id of ['upload-input', 'upload-folder-input']) {
      $(id).addEventListener('change', () => {
        const items = [...$(id).files]
          .map((file) => ({ file, path: file.webkitRelativePath || file.name }));
        $(id).value = '';  // the same file picked again is a change too
        if (items.length) this.start(items);
      });
    }
    $('upload-cancel').addEventListener('click', () => this.cancel());
    this.installDrop($('upload-drop'));
  }

  // hello: {tab_id, max_upload_bytes} of a new connection; null once it closed.
  connected(hello) {
    this.tabId = hello?.tab_id ?? null;
    this.maxBytes = hello?.max_upload_bytes ?? 0;
  }

  // Files dragged over the page show the overlay; dropped, they upload. The
  // overlay lets pointer events through, so enter and leave pair up on the
  // page's own elements.
  installDrop(overlay) {
    let depth = 0;
    const carriesFiles = (e) => [...(e.dataTransfer?.types ?? [])].includes('Files');
    document.addEventListener('dragenter', (e) => {
      if (!carriesFiles(e)) return;
      e.preventDefault();
      depth += 1;
      overlay.hidden = false;
    });
    document.addEventListener('dragover', (e) => {
      if (!carriesFiles(e)) return;
      e.preventDefault();
      e.dataTransfer.dropEffect = 'copy';
    });
    document.addEventListener('dragleave', (e) => {
      if (!carriesFiles(e)) return;
      depth = Math.max(0, depth - 1);
      if (depth === 0) overlay.hidden = true;
    });
    document.addEventListener('drop', (e) => {
      if (!carriesFiles(e)) return;
      e.preventDefault();
      depth = 0;
      overlay.hidden = true;
      this.dropped(e.dataTransfer);
    });
  }

  // The entries must be taken while the drop event runs; their files after.
  async dropped(dataTransfer) {
    const entries = [...dataTransfer.items].map((item) => item.webkitGetAsEntry?.()).filter(Boolean);
    const files = [...dataTransfer.files];
    if (this.running) {
      this.say('An upload is under way: wait for it, or cancel it first.', 'error');
      return;
    }
    try {
      const items = entries.length ? await walk(entries)
                                   : files.map((file) => ({ file, path: file.name }));
      this.start(items);
    } catch (e) {
      if (this.running) return;  // another upload began meanwhile
      this.failed({ code: 'INVALID_ARGUMENT',
                    message: `The dropped files could not be read: ${e.message}` });
    }
  }

  // items: [{file, path}] picked or dropped.
  async start(items) {
    if (this.running) {
      this.say('An upload is under way: wait for it, or cancel it first.', 'error');
      return;
    }
    this.lastError = null;
    // A new upload takes the panel: the previous one's volume still being
    // opened no longer sets its state.
    this.opening = null;
    if (!this.tabId) {
      this.failed({ code: 'UNAVAILABLE',
                    message: 'The web gateway is not connected; upload again once it is back.' });
      return;
    }
    let plan;
    try {
      plan = planUpload(items, this.maxBytes);
    } catch (e) {
      this.failed({ code: 'INVALID_ARGUMENT', message: e.message });
      return;
    }
    this.running = { name: plan.name, packing: null, xhr: null };
    this.showBar(0);
    this.$('upload-cancel').hidden = false;
    let blob = plan.blob;
    if (plan.kind === 'zip') {
      blob = await this.pack(plan);
      if (!blob) return;
    }
    if (!this.tabId) {  // the connection went while the files were packed
      this.failed({ code: 'UNAVAILABLE',
                    message: 'The web gateway is not connected; upload again once it is back.' });
      return;
    }
    this.send(blob, plan.name);
  }

  // The DICOM files as a stored ZIP; null when cancelled or unreadable.
  async pack(plan) {
    const packing = new AbortController();
    this.running.packing = packing;
    this.state('packing');
    const n = plan.entries.length;
    this.say(`Packing ${n} DICOM ${n === 1 ? 'file' : 'files'} into ${plan.name} ...`, 'info');
    try {
      return await storeZip(plan.entries, {
        signal: packing.signal,
        onProgress: (done, total) => {
          this.showBar(total ? done / total : 1);
          this.say(`Packing ${n} DICOM ${n === 1 ? 'file' : 'files'} into ${plan.name}: ` +
                   `${sizeText(done)} of ${sizeText(total)} read ...`, 'info');
        },
      });
    } catch (e) {
      if (packing.signal.aborted) this.cancelled();
      else this.failed({ code: 'INVALID_ARGUMENT',
                         message: `Packing ${plan.name} failed: ${e.message}` });
      return null;
    } finally {
      if (this.running) this.running.packing = null;
    }
  }

  send(blob, name) {
    const xhr = new XMLHttpRequest();
    this.running.xhr = xhr;
    this.state('sending');
    this.say(`Uploading ${name} (${sizeText(blob.size)}) ...`, 'info');
    xhr.open('POST', '/upload');
    xhr.setRequestHeader('Content-Type', 'application/octet-stream');
    xhr.setRequestHeader('X-Vpm-Tab', this.tabId);
    xhr.setRequestHeader('X-Vpm-File-Name', encodeURIComponent(name));
    // The browser may report the body sent after the gateway has already
    // said it passes it on or the server reads it (serverProgress): the
    // status never goes back to an earlier stage.
    const later = () => this.running?.xhr !== xhr || this.running.gatewayStage;
    xhr.upload.onprogress = (e) => {
      if (later()) return;
      this.showBar(e.total ? e.loaded / e.total : 0);
      this.say(`Uploading ${name}: ${sizeText(e.loaded)} of ${sizeText(blob.size)} sent ...`, 'info');
    };
    xhr.upload.onload = () => {
      if (later()) return;
      this.state('reading');
      this.showBar(null);
      this.say(`Uploaded ${name}; the gateway passes it to vpm-server ...`, 'info');
    };
    xhr.onload = () => this.answered(xhr, name);
    xhr.onerror = () => this.failed({
      code: 'UNAVAILABLE', message: `Uploading ${name} failed: the connection to the web gateway ` +
                                    'broke off.' });
    xhr.onabort = () => this.cancelled();
    xhr.send(blob);
  }

  // The gateway's progress (upload_progress): passing the file on, then the
  // server reading it.
  serverProgress(m) {
    const name = this.running?.name;
    if (!name || this.running.packing) return;
    this.running.gatewayStage = m.stage;
    this.state('reading');
    if (m.stage === 'sending') {
      this.showBar(m.total_bytes ? m.bytes / m.total_bytes : 1);
      this.say(`${name}: the gateway is passing it to vpm-server, ${sizeText(m.bytes)} of ` +
               `${sizeText(m.total_bytes)} ...`, 'info');
    } else if (m.stage === 'reading') {
      this.showBar(null);
      this.say(`${name}: reading on the server ...`, 'info');
    }
  }

  answered(xhr, name) {
    let body = null;
    try {
      body = JSON.parse(xhr.responseText);
    } catch { /* a plain-text answer: refused before the upload code ran */ }
    if (xhr.status === 200 && body?.volume) {
      this.finish('opening');
      this.lastVolume = body.volume;
      this.opening = body.volume.volume_id;
      this.say(`Uploaded ${name}; building the mesh and opening a session ...`, 'info');
      this.openVolume(body.volume);
      return;
    }
    this.failed({ code: body?.code ?? `HTTP ${xhr.status}`,
                  message: body?.message ?? `Uploading ${name} failed: HTTP ${xhr.status} ` +
                    `${xhr.responseText.trim().slice(0, 200)}` });
  }

  // The viewer opened a volume (app.js 'opened').
  opened(volume) {
    if (!this.opening || volume?.volume_id !== this.opening) return;
    this.opening = null;
    this.state('opened');
  }

  // The viewer could not open the uploaded volume (the page's error message
  // says why).
  viewerFailed(m) {
    if (!this.opening) return;
    this.opening = null;
    this.lastError = { code: m.code, message: m.message };
    this.state('error');
  }

  cancel() {
    if (!this.running) return;
    if (this.running.packing) this.running.packing.abort(new Error('cancelled'));
    else this.running.xhr?.abort();
  }

  cancelled() {
    const name = this.running?.name ?? 'the file';
    this.finish('cancelled');
    this.say(`The upload of ${name} was cancelled.`, 'info');
  }

  failed(error) {
    this.lastError = error;
    this.finish('error');
    this.say(error.message, 'error');
  }

  finish(state) {
    this.running = null;
    this.state(state);
    this.$('upload-progress').hidden = true;
    this.$('upload-cancel').hidden = true;
  }

  // The buttons give way to the bar and Cancel while an upload runs.
  state(name) {
    this.root.dataset.state = name;
    this.$('upload-file').hidden = Boolean(this.running);
    this.$('upload-folder').hidden = Boolean(this.running);
  }

  // fraction 0 to 1, or null: under way, how far unknown.
  showBar(fraction) {
    const bar = this.$('upload-progress');
    bar.hidden = false;
    if (fraction === null) bar.removeAttribute('value');
    else bar.value = fraction;
  }
}
