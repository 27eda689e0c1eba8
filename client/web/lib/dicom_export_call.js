// The Export button of one browser tab (docs/WEB.md, "Studies"): the tab's
// session as a derived DICOM series and a secondary capture, sent by
// vpm-server to a PACS endpoint (ExportDicom, a server stream of progress
// parts and a summary last; docs/PACS.md, "Export").
//
//   {type: 'export_dicom', endpoint, series_description}
//        -> {type: 'export_progress', endpoint, session_id, stage, fraction}...
//           {type: 'exported', summary, dropped_files}
//        or {type: 'pacs_error', action: 'export', code, message, endpoint}
//
// The request always names an endpoint, so the server sends the files to
// the PACS and none come back; should a part carry a file anyway, it is
// dropped here (counted in dropped_files): no DICOM file reaches a browser.
// One export at a time per tab; it is cancelled when the tab goes.
import { GrpcStatus } from './vpm_client.js';

// Warping, writing and sending a few hundred slices over a hospital network.
export const kExportDeadlineMs = 10 * 60 * 1000;

export class DicomExport {
  // connection: the tab's ViewerConnection (client, as, calls, session,
  // send, closed, pacs: its PacsCalls, whose failed() reports errors).
  constructor(connection) {
    this.connection = connection;
    this.call = null;
  }

  start({ endpoint, series_description: description = '' }) {
    const c = this.connection;
    const what = `Exporting to ${endpoint}`;
    const refuse = (message) => c.send({ type: 'pacs_error', action: 'export',
                                         code: 'FAILED_PRECONDITION', message, endpoint });
    if (this.call) return refuse(`${what}: an export of this tab is under way; wait for its end.`);
    if (!c.session) return refuse(`${what}: open a PACS series first.`);
    const sessionId = c.session.session_id;
    const call = c.client.exportDicom({ session_id: sessionId, endpoint,
                                        series_description: description }, c.as, kExportDeadlineMs);
    this.call = call;
    c.calls.add(call);
    let summary = null;
    let droppedFiles = 0;
    let status = null;
    let ended = false;
    const finish = () => {
      if (this.call !== call) return;
      this.call = null;
      c.calls.delete(call);
      if (c.closed) return;
      if (status.code !== GrpcStatus.OK) {
        c.pacs.failed('export', what, { code: status.code, details: status.details }, { endpoint });
      } else if (!summary) {
        c.pacs.failed('export', what, { code: GrpcStatus.INTERNAL,
                                        details: 'the server ended the export without a summary' },
                      { endpoint });
      } else {
        c.send({ type: 'exported', summary, dropped_files: droppedFiles });
      }
    };
    call.on('data', (part) => {
      if (part.summary) {
        summary = part.summary;
      } else if (part.file_name || part.data?.length) {
        droppedFiles += 1;
      } else {
        c.send({ type: 'export_progress', endpoint, session_id: sessionId, stage: part.stage,
                 fraction: part.fraction });
      }
    });
    // grpc-js emits 'status' after the last message was pushed and, on
    // failure, after 'error'; messages still buffered come before 'end'.
    call.on('error', () => {});
    call.on('status', (s) => {
      status = s;
      if (s.code !== GrpcStatus.OK || ended) finish();
    });
    call.on('end', () => {
      ended = true;
      if (status) finish();
    });
    c.send({ type: 'export_progress', endpoint, session_id: sessionId, stage: 'starting',
             fraction: 0 });
    return undefined;
  }
}
