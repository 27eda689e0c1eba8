// The Export to PACS button: the open session's deformed volume (a derived
// series) and its 3D view (a secondary capture) sent by vpm-server to the
// PACS the volume came from (ExportDicom through the gateway,
// lib/dicom_export_call.js). Enabled while the page shows a session of its
// own on a volume whose source is pacs:ENDPOINT/...; it exports to ENDPOINT.
//
// Element ids (stable, for end-to-end tests):
//   #export-pacs         the button (its text names the endpoint)
//   #export-description  optional SeriesDescription of the derived series
//   #export-progress     <progress> of the export (0 to 1), shown while it runs
// window.vpmViewer.lastExport holds the summary of the last export.
import { pacsEndpointOf } from './pacs_source.js';

const kMaxDescriptionChars = 64;  // ExportDicomRequest.series_description

export class ExportButton {
  // e: {button, description, progress}; send(message): to the gateway;
  // say(text, kind): the page's message line.
  constructor({ e, send, say }) {
    Object.assign(this, { e, send, say });
    this.endpoint = null;  // where the shown session would be exported to
    this.running = null;   // the endpoint of the export under way
    this.lastExport = null;
    e.button.addEventListener('click', () => this.start());
  }

  // view: {source, session, watching}: what the page shows.
  update({ source, session, watching }) {
    this.endpoint = session && !watching ? pacsEndpointOf(source) : null;
    const b = this.e.button;
    b.disabled = !this.endpoint || Boolean(this.running);
    // Shown only for a session on a PACS series: the volume row stays one
    // line otherwise.
    b.hidden = !this.endpoint && !this.running;
    this.e.description.hidden = b.hidden;
    b.textContent = this.endpoint ? `Export to PACS (${this.endpoint})` : 'Export to PACS';
    b.title = this.endpoint
      ? `Send the deformed volume and a capture of the 3D view to ${this.endpoint}, as new series ` +
        'of its study'
      : 'Open a series from a PACS (Studies) to export its deformed volume back to it';
  }

  start() {
    if (!this.endpoint || this.running) return;
    const description = this.e.description.value.trim();
    if (description.length > kMaxDescriptionChars) {
      this.say(`The series description is at most ${kMaxDescriptionChars} characters.`, 'error');
      return;
    }
    const message = { type: 'export_dicom', endpoint: this.endpoint };
    if (description) message.series_description = description;
    if (!this.send(message)) return;
    this.running = this.endpoint;
    this.e.button.disabled = true;
    this.progress({ stage: 'starting', fraction: 0 });
  }

  // m: {stage, fraction}.
  progress(m) {
    this.e.progress.hidden = false;
    this.e.progress.value = m.fraction;
    this.say(`Exporting to ${this.running}: ${m.stage} ${(100 * m.fraction).toFixed(0)}% ...`, 'info');
  }

  // m: {summary: ExportDicomSummary}.
  done(m) {
    const s = m.summary;
    this.finish();
    this.lastExport = s;
    this.say(`Sent ${s.instances} instances of series ${s.derived_series_uid} to ${s.endpoint}, ` +
             `study ${s.study_uid}.`, 'info');
  }

  // m: a pacs_error of action 'export'.
  failed(m) {
    this.finish();
    this.say(m.message, 'error');
  }

  finish() {
    this.running = null;
    this.e.progress.hidden = true;
    this.e.button.disabled = !this.endpoint;
  }
}
