// The Studies panel's calls for one browser tab (docs/WEB.md, "Studies";
// docs/PACS.md), made as the tab's signed-in user: the PACS endpoints the
// user may use, a study search, a study's series, and the load of a series
// with its progress. The page opens the loaded volume as it opens any
// loaded volume ({type: 'open', volume_id}).
//
//   {type: 'pacs_endpoints'}  ListPacsEndpoints -> {type: 'pacs_endpoints', endpoints, message}
//   {type: 'pacs_search', endpoint, ...query}  SearchStudies -> {type: 'pacs_studies',
//        endpoint, studies, truncated}
//   {type: 'pacs_series', endpoint, study_uid}  ListSeries -> {type: 'pacs_series',
//        endpoint, study_uid, series}
//   {type: 'pacs_open', source}  LoadVolume(source, progress_id) while GetLoadProgress is
//        polled -> {type: 'pacs_progress', source, stage, fraction}... then
//        {type: 'pacs_loaded', source, volume}
//   {type: 'pacs_cancel'}  cancels the load under way -> {type: 'pacs_error', action: 'open',
//        code: 'CANCELLED', ...}
//   {type: 'pacs_thumbnail', endpoint, study_uid, series_uid}  GetSeriesThumbnail (96 px) ->
//        {type: 'pacs_thumbnail', endpoint, study_uid, series_uid, data_url, width, height},
//        or the same with code and message (no data_url) when there is none: a
//        thumbnail's failure is the series row's, not the panel's. At most
//        kThumbnailsAtOnce run at once per tab, kMaxQueuedThumbnails wait.
// A failure is {type: 'pacs_error', action ('endpoints' | 'search' | 'series' | 'open' |
// 'export'), code, message, endpoint | source}. A newer search (or series
// listing, or load) supersedes the one under way: only its answer comes back.
//
// Patient names, IDs and birth dates reach only the page: the gateway's log
// gets the action, the endpoint and the status code, never a query value or
// the server's text.
import crypto from 'node:crypto';

import { parsePacsSource } from '../public/pacs_source.js';
import { explainError } from './explain_error.js';
import { explainPacsError, noPacs } from './explain_pacs_error.js';
import { GrpcStatus, isServerDown, statusName } from './vpm_client.js';

const kProgressPollMs = 250;
// A series of a few hundred MiB over a hospital network takes minutes; the
// server ends a transfer that stalls for 60 s itself.
export const kPacsLoadDeadlineMs = 10 * 60 * 1000;
export const kThumbnailPx = 96;
export const kThumbnailsAtOnce = 3;
export const kMaxQueuedThumbnails = 200;
const kThumbnailDeadlineMs = 40 * 1000;  // the server gives up at 30 s
const kQueryKeys = ['patient_name', 'patient_id', 'patient_birth_date', 'study_date', 'modality',
                    'accession_number', 'limit'];

// What the panel shows of a StudyInfo (counts: -1 when the PACS did not say).
function studySummary(s) {
  return {
    study_uid: s.study_uid, patient_name: s.patient_name, patient_id: s.patient_id,
    patient_birth_date: s.patient_birth_date, study_date: s.study_date,
    study_description: s.study_description, accession_number: s.accession_number,
    modalities: s.modalities ?? [], series_count: Number(s.series_count),
    instance_count: Number(s.instance_count),
  };
}

function seriesSummary(s) {
  return {
    series_uid: s.series_uid, modality: s.modality, description: s.description,
    body_part: s.body_part, series_number: Number(s.series_number),
    instance_count: Number(s.instance_count), source: s.source,
  };
}

// A pending-call set (vpm_client.js call()) that records each call in two sets.
const inBoth = (a, b) => ({
  add: (call) => { a.add(call); b.add(call); },
  delete: (call) => { a.delete(call); b.delete(call); },
});

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

export class PacsCalls {
  // connection: the tab's ViewerConnection (rpc, send, log, client, as,
  // calls, closed, serverDown).
  constructor(connection) {
    this.connection = connection;
    this.searchOp = 0;
    this.seriesOp = 0;
    this.load = null;  // {source, calls, done}: the load under way
    this.thumbnails = { running: 0, queue: [] };
  }

  async endpoints() {
    const c = this.connection;
    try {
      const { endpoints } = await c.rpc('ListPacsEndpoints', {});
      c.send({ type: 'pacs_endpoints', endpoints,
               message: endpoints.length ? '' : 'No PACS endpoint you may use: this server was ' +
                 'started without --pacs, or its --pacs file does not list you for any.' });
    } catch (err) {
      if (noPacs(err)) {
        c.send({ type: 'pacs_endpoints', endpoints: [],
                 message: 'This server has no PACS (started without --pacs).' });
        return;
      }
      if (err?.code === GrpcStatus.UNIMPLEMENTED) {
        c.send({ type: 'pacs_endpoints', endpoints: [],
                 message: 'This vpm-server does not list PACS endpoints (an older version): the ' +
                   'Studies panel needs a newer one.' });
        return;
      }
      await this.failed('endpoints', 'Listing the PACS endpoints', err);
    }
  }

  async search(message) {
    const c = this.connection;
    const op = ++this.searchOp;
    const { endpoint } = message;
    const request = { endpoint };
    for (const key of kQueryKeys) if (message[key] !== undefined) request[key] = message[key];
    try {
      const r = await c.rpc('SearchStudies', request);
      if (op !== this.searchOp) return;
      c.send({ type: 'pacs_studies', endpoint, studies: r.studies.map(studySummary),
               truncated: Boolean(r.truncated) });
    } catch (err) {
      if (op === this.searchOp) await this.failed('search', `Searching ${endpoint}`, err, { endpoint });
    }
  }

  async series({ endpoint, study_uid: studyUid }) {
    const c = this.connection;
    const op = ++this.seriesOp;
    try {
      const { series } = await c.rpc('ListSeries', { endpoint, study_uid: studyUid });
      if (op !== this.seriesOp) return;
      c.send({ type: 'pacs_series', endpoint, study_uid: studyUid, series: series.map(seriesSummary) });
    } catch (err) {
      if (op === this.seriesOp) {
        await this.failed('series', `Listing the series of study ${studyUid}`, err,
                          { endpoint, study_uid: studyUid });
      }
    }
  }

  // Queues a thumbnail; one past kMaxQueuedThumbnails is answered
  // RESOURCE_EXHAUSTED at once.
  thumbnail({ endpoint, study_uid: studyUid, series_uid: seriesUid }) {
    const t = this.thumbnails;
    const reply = { type: 'pacs_thumbnail', endpoint, study_uid: studyUid, series_uid: seriesUid };
    if (t.queue.length >= kMaxQueuedThumbnails) {
      this.connection.send({ ...reply, code: 'RESOURCE_EXHAUSTED',
                             message: 'Too many thumbnails asked at once; scroll back to retry.' });
      return;
    }
    t.queue.push(reply);
    this.pumpThumbnails();
  }

  pumpThumbnails() {
    const t = this.thumbnails;
    while (t.running < kThumbnailsAtOnce && t.queue.length && !this.connection.closed) {
      const reply = t.queue.shift();
      t.running += 1;
      this.runThumbnail(reply).finally(() => {
        t.running -= 1;
        this.pumpThumbnails();
      });
    }
  }

  async runThumbnail(reply) {
    const c = this.connection;
    try {
      const r = await c.client.call('GetSeriesThumbnail',
                                    { endpoint: reply.endpoint, study_uid: reply.study_uid,
                                      series_uid: reply.series_uid, size_px: kThumbnailPx },
                                    c.as, c.closed ? null : c.calls, kThumbnailDeadlineMs);
      c.send({ ...reply, width: r.width, height: r.height,
               data_url: `data:image/png;base64,${Buffer.from(r.png).toString('base64')}` });
    } catch (err) {
      if (c.closed) return;
      c.log(`PACS thumbnail on ${reply.endpoint}: ${statusName(err?.code)}`);
      c.send({ ...reply, code: statusName(err?.code),
               message: explainPacsError(err, 'The thumbnail', c.client.address) });
    }
  }

  // LoadVolume with a progress id; GetLoadProgress is polled meanwhile and
  // each new stage or fraction goes to the page.
  async open({ source }) {
    const c = this.connection;
    this.cancelLoad();
    const load = { source, calls: new Set(), done: false };
    this.load = load;
    const progressId = crypto.randomUUID();
    const what = `Opening ${source.split('/').at(-1)}`;  // the series UID
    c.send({ type: 'pacs_progress', source, stage: 'queued', fraction: 0 });
    try {
      const loading = c.client.call('LoadVolume', { source, progress_id: progressId }, c.as,
                                    this.pending(load), kPacsLoadDeadlineMs);
      this.pollProgress(load, progressId);
      const volume = await loading;
      if (this.load !== load || c.closed) return;
      c.send({ type: 'pacs_loaded', source, volume });
    } catch (err) {
      if (this.load === load) await this.failed('open', what, err, { source });
    } finally {
      load.done = true;
      if (this.load === load) this.load = null;
    }
  }

  // Cancels the load under way (its LoadVolume and polls): the server stops
  // the retrieval at its next poll of the call.
  cancelLoad() {
    const load = this.load;
    if (!load) return false;
    for (const call of load.calls) call.cancel();
    return true;
  }

  pending(load) {
    const c = this.connection;
    return c.closed ? null : inBoth(c.calls, load.calls);
  }

  async pollProgress(load, progressId) {
    const c = this.connection;
    let last = 'queued 0.000';  // what open() sent
    while (!load.done && !c.closed) {
      await sleep(kProgressPollMs);
      if (load.done || this.load !== load) return;
      let p;
      try {
        p = await c.client.call('GetLoadProgress', { progress_id: progressId }, c.as,
                                this.pending(load));
      } catch {
        continue;  // NOT_FOUND until the server has started the load; LoadVolume reports the rest
      }
      if (load.done || this.load !== load) return;
      const shown = `${p.stage} ${p.fraction.toFixed(3)}`;
      if (shown !== last) {
        last = shown;
        c.send({ type: 'pacs_progress', source: load.source, stage: p.stage, fraction: p.fraction });
      }
      if (p.done) return;
    }
  }

  // A PACS call failed: the page is told in the panel. UNAVAILABLE (or a
  // deadline) is the PACS's when vpm-server still answers, else the server's
  // (the page's server state then turns red, as for any call).
  async failed(action, what, err, extra = {}) {
    const c = this.connection;
    if (c.closed) return;  // the tab went: its calls were cancelled
    const endpoint = extra.endpoint ?? parsePacsSource(extra.source)?.endpoint;
    c.log(`PACS ${action}${endpoint ? ` on ${endpoint}` : ''}: ${statusName(err?.code)}`);
    let message;
    if (isServerDown(err) && !(await this.serverAnswers())) {
      message = explainError(err, what, c.client.address);
      c.serverDown(err);
    } else {
      message = explainPacsError(err, what, c.client.address);
    }
    c.send({ type: 'pacs_error', action, code: statusName(err?.code), message, ...extra });
  }

  async serverAnswers() {
    try {
      await this.connection.rpc('ListVolumes', {});
      return true;
    } catch {
      return false;
    }
  }
}
