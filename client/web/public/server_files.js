// The "Server files" section of the Studies panel: the folders and volume
// files under the server's --data-root (docs/WEB.md, "Server files"; the
// gateway's side is lib/data_root_calls.js). Shown only to users the
// server's users file allows (browse-data-root): the first listing of the
// root answers, else the section stays hidden. A folder opens on a click;
// Open loads a volume file, a DICOM folder or an archive as a source.
//
// Element ids (stable: end-to-end tests drive it through them):
//   #server-files        the section; data-state: hidden | listing | listed | error
//   #server-files-up     the folder above
//   #server-files-path   the folder shown, relative to the data root
//   #server-files-note   what the section says (data-kind: info | error)
//   #server-files-body   <tbody>: one <tr data-name data-kind> per entry;
//                        folders have a <button class="server-folder">,
//                        what opens a <button class="server-open">

const kKinds = {
  FOLDER: 'folder',
  DICOM_FOLDER: 'DICOM series',
  VOLUME_FILE: 'volume',
  ARCHIVE: 'archive',
  OTHER_FILE: 'file',
  NOT_OPENABLE: 'cannot be opened',
};

function cell(text, className) {
  const td = document.createElement('td');
  td.textContent = text;
  if (className) td.className = className;
  return td;
}

function shownSize(bytes) {
  if (bytes <= 0) return '';
  const units = ['B', 'kB', 'MB', 'GB', 'TB'];
  let v = bytes;
  let u = 0;
  while (v >= 1000 && u < units.length - 1) {
    v /= 1000;
    u += 1;
  }
  return `${v < 10 && u ? v.toFixed(1) : Math.round(v)} ${units[u]}`;
}

const button = (text, className, title, onClick) => {
  const b = document.createElement('button');
  b.type = 'button';
  b.className = className;
  b.textContent = text;
  b.title = title;
  b.addEventListener('click', onClick);
  return b;
};

export class ServerFiles {
  // $: id -> element; send(message): to the gateway (false when it is not
  // connected); openSource(source): opens a source as the volume picker does.
  constructor({ $, send, openSource }) {
    Object.assign(this, { $, send, openSource });
    this.root = $('server-files');
    this.path = '';
    this.root.dataset.state = 'hidden';
    $('server-files-up').addEventListener('click', () => {
      this.list(this.path.split('/').slice(0, -1).join('/'));
    });
  }

  // Lists the folder shown again (the panel opened).
  refresh() {
    this.list(this.path);
  }

  list(path) {
    if (!this.send({ type: 'data_ls', path })) return;
    this.asked = path;
    if (!this.root.hidden) this.root.dataset.state = 'listing';
  }

  say(text, kind = 'info') {
    this.$('server-files-note').textContent = text;
    this.$('server-files-note').dataset.kind = kind;
  }

  // m: {path, entries, truncated}.
  show(m) {
    this.path = m.path;
    this.root.hidden = false;
    this.root.dataset.state = 'listed';
    this.$('server-files-path').textContent = `/${m.path}`;
    this.$('server-files-up').disabled = m.path === '';
    this.$('server-files-body').replaceChildren(...m.entries.map((e) => this.row(e)));
    this.say(m.truncated ? 'More entries than the server lists: the first ones by name.'
                         : `${m.entries.length} entries.`);
  }

  row(e) {
    const tr = document.createElement('tr');
    tr.dataset.name = e.name;
    tr.dataset.kind = e.kind;
    const folder = e.kind === 'FOLDER' || e.kind === 'DICOM_FOLDER';
    const name = cell(folder ? '' : e.name);
    if (folder) {
      const inside = this.path ? `${this.path}/${e.name}` : e.name;
      name.append(button(`${e.name}/`, 'server-folder', 'List this folder', () => this.list(inside)));
    }
    const actions = cell('');
    if (e.source) {
      actions.append(button('Open', 'server-open', `Load ${e.source} on the server and open it`,
                            () => this.openSource(e.source)));
    }
    const modified = e.modified_unix_ms
      ? new Date(e.modified_unix_ms).toISOString().slice(0, 16).replace('T', ' ') : '';
    tr.append(name, cell(kKinds[e.kind] ?? e.kind), cell(shownSize(e.size_bytes), 'number'),
              cell(modified, 'number'), actions);
    return tr;
  }

  // m: {path, code, message, allowed}: a user who may not browse never
  // sees the section.
  failed(m) {
    if (!m.allowed) {
      this.root.hidden = true;
      this.root.dataset.state = 'hidden';
      return;
    }
    this.root.dataset.state = 'error';
    this.say(m.message, 'error');
  }
}
