// The case messages of one browser tab (docs/CASES.md, docs/WEB.md "Cases"),
// called as the tab's signed-in user: the list of their cases and those
// shared with them, rename, delete, and undo/redo in the tab's session.
// Opening a case attaches the tab's stream, so it is the connection's own
// (ViewerConnection.openCase). After each change the list is sent again.
//
//   {type: 'cases'}                      -> {type: 'cases', kept, cases, message}
//   {type: 'rename_case', case_id, title} UpdateCase -> {type: 'case_renamed', case}
//   {type: 'delete_case', case_id}       DeleteCase -> {type: 'case_deleted', case_id, current}
//   {type: 'undo', redo}                 Undo -> {type: 'undone', redo, changed, events,
//                                        undone, max_displacement_mm, case_id}
// A server started without --state-dir answers FAILED_PRECONDITION: the list
// comes back with kept: false and a message saying so.
import { explainError } from './explain_error.js';
import { GrpcStatus } from './vpm_client.js';

// A CaseInfo as the page gets it: what the panel shows (no mesh parameters),
// with `mine`: the tab's user owns it (may open, rename, delete it): true,
// false, or null when not known. The server names users as its users file
// (or `default` for its --token) does, which need not be the gateway's name
// (the viewer token's user is `viewer`): `serverUser`, once a SessionInfo
// of this tab named its owner, decides; before that only an equal name does.
// Displacements are in mm, times in ms since the Unix epoch.
export function caseSummary(info, user, serverUser = null) {
  let mine = info.owner === user ? true : null;
  if (serverUser) mine = info.owner === serverUser;
  return {
    case_id: info.case_id,
    title: info.title,
    owner: info.owner,
    mine,
    shared_with: info.shared_with ?? [],
    source: info.source,
    events: Number(info.events),
    undone: Number(info.undone),
    max_displacement_mm: info.max_displacement_mm,
    created_unix_ms: Number(info.created_unix_ms),
    modified_unix_ms: Number(info.modified_unix_ms),
    session_id: info.session_id,  // its open session; '' when closed
  };
}

const noCases = (err) => err?.code === GrpcStatus.FAILED_PRECONDITION &&
  /keeps no cases/.test(err?.details ?? '');

export class CaseCalls {
  // connection: the tab's ViewerConnection (rpc, send, fail, user,
  // serverUser, session, watching, stopStream, startStream, record).
  constructor(connection) {
    this.connection = connection;
  }

  async list() {
    const c = this.connection;
    try {
      const { cases } = await c.rpc('ListCases', {});
      c.send({ type: 'cases', kept: true,
               cases: cases.map((info) => caseSummary(info, c.user, c.serverUser)) });
    } catch (err) {
      if (noCases(err)) {
        c.send({ type: 'cases', kept: false, cases: [],
                 message: explainError(err, null, c.client.address) });
        return;
      }
      c.fail('Listing cases', err);
    }
  }

  async rename({ case_id: caseId, title }) {
    const c = this.connection;
    try {
      const info = await c.rpc('UpdateCase', { case_id: caseId, title });
      c.send({ type: 'case_renamed', case: caseSummary(info, c.user, c.serverUser) });
    } catch (err) {
      c.fail(`Renaming case ${caseId}`, err, { case_id: caseId });
    }
    await this.list();
  }

  // The tab's own case: its stream stops first (the server ends it when the
  // case goes) and the session is forgotten without a CloseSession (the
  // server closed it); should the delete fail, the stream starts again.
  async delete({ case_id: caseId }) {
    const c = this.connection;
    const current = !c.watching && c.session?.case_id === caseId;
    if (current) c.stopStream();
    try {
      await c.rpc('DeleteCase', { case_id: caseId });
      if (current && c.session?.case_id === caseId) {
        c.record.closed(c.session.session_id);
        c.session = null;
      }
      c.send({ type: 'case_deleted', case_id: caseId, current });
    } catch (err) {
      if (current && c.session?.case_id === caseId && !c.call) c.startStream();
      c.fail(`Deleting case ${caseId}`, err, { case_id: caseId });
    }
    await this.list();
  }

  // Undo (or redo) the last action of the tab's session; the new frame comes
  // through the stream (the server notifies its streams after an undo).
  async undo({ redo = false }) {
    const c = this.connection;
    const what = redo ? 'Redo' : 'Undo';
    if (!c.session || c.watching) {
      c.send({ type: 'error', what,
               message: `${what}: ${c.watching ? 'a watched session is its owner\'s to change'
                                               : 'open a volume or a case first'}.` });
      return;
    }
    const { session_id: sessionId, case_id: caseId } = c.session;
    try {
      const r = await c.rpc('Undo', { session_id: sessionId, redo });
      c.send({ type: 'undone', redo, case_id: caseId, changed: r.changed,
               events: Number(r.events), undone: Number(r.undone),
               max_displacement_mm: r.max_displacement_mm });
    } catch (err) {
      c.fail(what, err, { case_id: caseId });
      return;
    }
    await this.list();
  }
}
