// The Cases panel: the signed-in user's cases and those shared with them
// (ListCases through the gateway, newest change first): title, owner, last
// change, events in effect, largest displacement (mm) and whether a session
// has it open, with Open, Rename and Delete for the user's own cases (and
// those the gateway cannot tell yet: case_calls.js caseSummary). It
// shows what the gateway sends ({type: 'cases'}); the gateway sends the list
// again after each rename, delete and undo, the page asks after each open.

const kMaxTitleBytes = 256;  // UpdateCaseRequest.title

function cell(text, className) {
  const td = document.createElement('td');
  td.textContent = text;
  if (className) td.className = className;
  return td;
}

function button(label, title, onClick) {
  const b = document.createElement('button');
  b.type = 'button';
  b.textContent = label;
  b.title = title;
  b.addEventListener('click', onClick);
  return b;
}

export class CasesPanel {
  // body: the table's <tbody>; note: an element for what the panel says
  // (no cases kept, none yet); open(caseId), rename(caseId, title),
  // remove(caseId): what the buttons do; currentCaseId(): the case shown.
  constructor({ body, note, open, rename, remove, currentCaseId }) {
    Object.assign(this, { body, note, open, rename, remove, currentCaseId });
    this.cases = [];
    this.kept = null;  // false: the server keeps no cases
  }

  // m: {kept, cases, message}.
  show(m) {
    this.kept = m.kept;
    this.cases = m.cases ?? [];
    this.note.textContent = !m.kept ? m.message
      : (this.cases.length ? '' : 'No cases yet: open a volume and each session is kept as one.');
    this.note.dataset.kind = m.kept ? 'info' : 'error';
    this.render();
  }

  // Marks the current case again (after an open, without a new list).
  render() {
    this.body.replaceChildren(...this.cases.map((c) => this.row(c)));
  }

  row(c) {
    const tr = document.createElement('tr');
    tr.dataset.caseId = c.case_id;
    if (c.case_id === this.currentCaseId()) tr.dataset.current = 'true';
    const title = cell(c.title || '(untitled)', 'title');
    title.title = `${c.case_id}\n${c.source}`;
    tr.append(
      title,
      cell(c.mine === true ? `${c.owner} (you)` : c.owner, 'owner'),
      cell(new Date(c.modified_unix_ms).toLocaleString(), 'modified'),
      cell(String(c.events) + (c.undone ? ` (+${c.undone} undone)` : ''), 'events'),
      cell(`${c.max_displacement_mm.toFixed(2)} mm`, 'displacement'),
      cell(c.session_id ? 'open' : 'closed', 'state'));
    const actions = document.createElement('td');
    actions.className = 'actions';
    if (c.mine !== false) {  // null: not known yet (the server refuses what is not the user's)
      actions.append(
        button('Open', 'Open this case where it was left (its open session, or replayed)',
               () => this.open(c.case_id)),
        button('Rename', 'Give the case a new title', () => this.askRename(c)),
        button('Delete', 'Delete the case and everything stored of it', () => this.askDelete(c)));
    } else {
      actions.textContent = `shared with you by ${c.owner}`;
    }
    tr.append(actions);
    return tr;
  }

  askRename(c) {
    const title = window.prompt(`New title for case ${c.case_id}:`, c.title)?.trim();
    if (!title || title === c.title) return;
    if (new TextEncoder().encode(title).length > kMaxTitleBytes) {
      window.alert(`A title is at most ${kMaxTitleBytes} bytes.`);
      return;
    }
    this.rename(c.case_id, title);
  }

  askDelete(c) {
    const open = c.case_id === this.currentCaseId() ? ' It is the case on screen: the view stops.' : '';
    if (window.confirm(`Delete case "${c.title}" (${c.case_id}) and its ${c.events} events? ` +
                       `This cannot be undone.${open}`)) {
      this.remove(c.case_id);
    }
  }

  find(caseId) {
    return this.cases.find((c) => c.case_id === caseId) ?? null;
  }
}
