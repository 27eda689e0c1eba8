// The Studies panel: search a PACS the server reaches and open one of its
// series in the viewer (docs/WEB.md, "Studies"; the gateway's side is
// lib/pacs_calls.js). It lists the endpoints the user may use (or says why
// there are none), searches studies, lists a clicked study's series, and
// opens a series: the gateway loads it (LoadVolume with its progress shown
// here), then the page opens the loaded volume as it opens any volume of its
// list (`openVolume`, app.js). Errors of the server show in the panel.
//
// Element ids (stable: end-to-end tests drive the panel through them):
//   #studies-toggle     button that opens and closes the panel (also F2)
//   #studies            the panel; data-state: idle | searching | listing |
//                       loading | opening | opened | error
//   #studies-close      closes it
//   #pacs-endpoint      <select> of the endpoints the user may use
//   #pacs-note          what the panel says (data-kind: info | error)
//   #pacs-search-form   the search form; its fields:
//     #pacs-patient-name (wildcards * and ?, DOE^J*), #pacs-patient-id,
//     #pacs-birth-date, #pacs-study-date-from, #pacs-study-date-to (date
//     inputs: YYYY-MM-DD), #pacs-modality (CT, MR ...), #pacs-accession
//   #pacs-search        submits the search
//   #pacs-studies-body  <tbody>: one <tr data-study-uid> per study; a click
//                       (or Enter) lists its series
//   #pacs-truncated     shown when more studies match than were listed
//   #pacs-series-body   <tbody>: one <tr data-series-uid data-modality> per
//                       series, each with a <button class="pacs-open"> and an
//                       <img class="pacs-thumb" data-state="waiting|asked|shown|none">:
//                       the series' thumbnail, asked of the gateway once the
//                       row is visible (one pacs_thumbnail per series)
//   #pacs-progress      <progress> of the load (0 to 1), #pacs-progress-label
//   #pacs-cancel        cancels the load under way
import { personName, searchMessage, shownDate } from './pacs_query.js';

// What the server's load stages mean to a user (LoadProgress.stage).
const kStages = {
  queued: 'waiting for the server',
  retrieving: 'retrieving from the PACS',
  reading: 'reading the DICOM files',
  uploading: 'uploading to the GPU',
  done: 'loaded',
  failed: 'failed',
};

function cell(text, className) {
  const td = document.createElement('td');
  td.textContent = text;
  if (className) td.className = className;
  return td;
}

const count = (n) => (n >= 0 ? String(n) : '?');  // -1: the PACS did not say

export class StudiesPanel {
  // $: id -> element; send(message): to the gateway (false when it is not
  // connected); openVolume(volume): opens a loaded volume as the page's
  // volume list does.
  constructor({ $, send, openVolume, onOpen = () => {} }) {
    Object.assign(this, { $, send, openVolume, onOpen });
    // Thumbnails are asked for the rows that come into view only.
    this.thumbnailWatch = new IntersectionObserver((entries) => {
      for (const e of entries) if (e.isIntersecting) this.askThumbnail(e.target);
    });
    this.root = $('studies');
    this.endpoints = null;     // names the user may use, once listed
    this.studies = [];
    this.studiesEndpoint = null;  // the endpoint the listed studies are on
    this.truncated = false;
    this.studyUid = null;      // the study whose series are listed
    this.series = [];
    this.loading = null;       // the source being loaded
    this.opening = null;       // the source loaded and being opened
    this.lastError = null;     // the last pacs_error (for tests)
    $('studies-toggle').addEventListener('click', () => this.toggle());
    $('studies-close').addEventListener('click', () => this.toggle(false));
    $('pacs-search-form').addEventListener('submit', (e) => {
      e.preventDefault();
      this.search();
    });
    $('pacs-cancel').addEventListener('click', () => this.cancelLoad());
    this.root.addEventListener('keydown', (e) => {
      if (e.key === 'Escape') this.toggle(false);
    });
    // The rows above move (a message of two lines, a window resized).
    new ResizeObserver(() => {
      if (this.isOpen) this.place();
    }).observe(document.body);
  }

  get isOpen() {
    return !this.root.hidden;
  }

  // Opens (or closes) the panel; opening asks for the endpoints again.
  toggle(open = !this.isOpen) {
    this.root.hidden = !open;
    this.$('studies-toggle').setAttribute('aria-expanded', String(open));
    if (!open) return;
    this.place();
    this.send({ type: 'pacs_endpoints' });
    this.onOpen();
    this.$('pacs-patient-name').focus();
  }

  // The panel floats just below the row of its toggle (the volume picker),
  // so that Open, Studies and Export stay in reach while it is open.
  place() {
    const topPx = Math.max(8, Math.round(this.$('studies-toggle').parentElement
      .getBoundingClientRect().bottom + 6));
    this.root.style.top = `${topPx}px`;
    this.root.style.maxHeight = `calc(100vh - ${topPx + 8}px)`;
  }

  // send(), saying so in the panel when the gateway is away.
  post(message) {
    if (this.send(message)) return true;
    this.say('The web gateway is not connected; try again once it is back.', 'error', 'error');
    return false;
  }

  say(text, kind = 'info', state = null) {
    this.$('pacs-note').textContent = text;
    this.$('pacs-note').dataset.kind = kind;
    if (state) this.root.dataset.state = state;
  }

  // m: {endpoints, message}: message says why there are none.
  showEndpoints(m) {
    const select = this.$('pacs-endpoint');
    const before = select.value;
    this.endpoints = m.endpoints;
    select.replaceChildren(...m.endpoints.map((name) => new Option(name, name)));
    if (m.endpoints.includes(before)) select.value = before;
    select.disabled = m.endpoints.length === 0;
    this.$('pacs-search').disabled = m.endpoints.length === 0;
    if (!m.endpoints.length) this.say(m.message, 'error', 'idle');
    else if (this.root.dataset.state === 'idle') this.say('');
  }

  search() {
    let message;
    try {
      message = searchMessage(this.$('pacs-endpoint').value, {
        patient_name: this.$('pacs-patient-name').value,
        patient_id: this.$('pacs-patient-id').value,
        birth_date: this.$('pacs-birth-date').value,
        study_date_from: this.$('pacs-study-date-from').value,
        study_date_to: this.$('pacs-study-date-to').value,
        modality: this.$('pacs-modality').value,
        accession_number: this.$('pacs-accession').value,
      });
    } catch (e) {
      this.say(`Search: ${e.message}.`, 'error', 'error');
      return;
    }
    if (!this.post(message)) return;
    this.say(`Searching ${message.endpoint} ...`, 'info', 'searching');
    this.showStudies({ endpoint: null, studies: [], truncated: false });
  }

  // m: {endpoint, studies, truncated}; endpoint null: none listed.
  showStudies(m) {
    Object.assign(this, { studies: m.studies, truncated: m.truncated, studiesEndpoint: m.endpoint,
                          studyUid: null });
    this.$('pacs-studies-body').replaceChildren(...m.studies.map((s) => this.studyRow(s)));
    this.$('pacs-truncated').hidden = !m.truncated;
    this.showSeries({ study_uid: null, series: [] });
    if (!m.endpoint) return;
    const n = m.studies.length;
    this.say(n ? `${n} ${n === 1 ? 'study' : 'studies'} on ${m.endpoint}; click one for its series.`
               : `No study on ${m.endpoint} matches.`, 'info', 'idle');
  }

  studyRow(s) {
    const tr = document.createElement('tr');
    tr.dataset.studyUid = s.study_uid;
    tr.tabIndex = 0;
    tr.title = `Study ${s.study_uid}${s.accession_number ? `, accession ${s.accession_number}` : ''}`;
    tr.append(cell(personName(s.patient_name)), cell(s.patient_id),
              cell(shownDate(s.patient_birth_date), 'date'), cell(shownDate(s.study_date), 'date'),
              cell(s.study_description), cell(s.modalities.join(' ')), cell(count(s.series_count), 'number'));
    const pick = () => this.listSeries(s.study_uid);
    tr.addEventListener('click', pick);
    tr.addEventListener('keydown', (e) => {
      if (e.key === 'Enter') pick();
    });
    return tr;
  }

  listSeries(studyUid) {
    const endpoint = this.studiesEndpoint;
    if (!this.post({ type: 'pacs_series', endpoint, study_uid: studyUid })) return;
    this.studyUid = studyUid;
    for (const tr of this.$('pacs-studies-body').children) {
      tr.dataset.selected = String(tr.dataset.studyUid === studyUid);
    }
    this.showSeries({ study_uid: studyUid, series: [] });
    this.say('Listing the series ...', 'info', 'listing');
  }

  // m: {study_uid, series}; a listing of another study than the one
  // clicked last is stale.
  showSeries(m) {
    if (m.study_uid !== this.studyUid) return;
    this.series = m.series;
    this.thumbnailWatch.disconnect();
    this.$('pacs-series-body').replaceChildren(...m.series.map((s) => this.seriesRow(s)));
    if (m.study_uid) {
      this.say(m.series.length ? `${m.series.length} series; Open loads one into the viewer.`
                               : 'This study has no series.', 'info', 'idle');
    }
  }

  seriesRow(s) {
    const tr = document.createElement('tr');
    tr.dataset.seriesUid = s.series_uid;
    tr.dataset.modality = s.modality;
    tr.title = `Series ${s.series_uid}`;
    const open = document.createElement('button');
    open.type = 'button';
    open.className = 'pacs-open';
    open.textContent = 'Open';
    open.title = 'Load this series on the server and open it in the viewer';
    open.addEventListener('click', () => this.openSeries(s));
    const actions = cell('');
    actions.append(open);
    const thumb = document.createElement('img');
    thumb.className = 'pacs-thumb';
    thumb.alt = '';
    thumb.dataset.state = 'waiting';
    const preview = cell('', 'thumb');
    preview.append(thumb);
    tr.dataset.endpoint = this.studiesEndpoint ?? '';
    this.thumbnailWatch.observe(tr);
    tr.append(preview, cell(s.series_number >= 0 ? String(s.series_number) : '', 'number'), cell(s.modality),
              cell(s.description), cell(s.body_part), cell(count(s.instance_count), 'number'), actions);
    return tr;
  }

  // A series row came into view: its thumbnail is asked for, once.
  askThumbnail(tr) {
    this.thumbnailWatch.unobserve(tr);
    const img = tr.querySelector('img.pacs-thumb');
    if (!img || img.dataset.state !== 'waiting' || !this.studyUid) return;
    if (this.send({ type: 'pacs_thumbnail', endpoint: tr.dataset.endpoint,
                    study_uid: this.studyUid, series_uid: tr.dataset.seriesUid })) {
      img.dataset.state = 'asked';
    }
  }

  // m: {study_uid, series_uid, data_url, width, height} or {..., code,
  // message}: the row's thumbnail, or why there is none (its tooltip).
  showThumbnail(m) {
    if (m.study_uid !== this.studyUid) return;
    const row = [...this.$('pacs-series-body').rows].find((r) => r.dataset.seriesUid === m.series_uid);
    const img = row?.querySelector('img.pacs-thumb');
    if (!img) return;
    if (m.data_url) {
      img.src = m.data_url;
      img.alt = 'thumbnail';
      img.dataset.state = 'shown';
    } else {
      img.dataset.state = 'none';
      img.title = m.message ?? 'No thumbnail';
    }
  }

  openSeries(s) {
    this.openSource(s.source, `series ${s.series_number >= 0 ? s.series_number : ''} ` +
                    `(${s.modality} ${s.description})`);
  }

  // source: pacs:ENDPOINT/STUDY_UID/SERIES_UID[?stack=N]; what: its name for
  // the panel's note.
  openSource(source, what) {
    if (!this.post({ type: 'pacs_open', source })) return;
    Object.assign(this, { loading: source, opening: null });
    this.showProgress({ stage: 'queued', fraction: 0 });
    this.say(`Opening ${what} ...`, 'info', 'loading');
  }

  // m: {source, stage, fraction}.
  showProgress(m) {
    if (m.source !== undefined && m.source !== this.loading) return;
    const bar = this.$('pacs-progress');
    bar.hidden = false;
    bar.value = m.fraction;
    this.$('pacs-progress-label').textContent =
      `${kStages[m.stage] ?? m.stage} ${(100 * m.fraction).toFixed(0)}%`;
    this.$('pacs-cancel').hidden = false;
  }

  hideProgress() {
    this.$('pacs-progress').hidden = true;
    this.$('pacs-progress-label').textContent = '';
    this.$('pacs-cancel').hidden = true;
  }

  // m: {source, volume}: the series is loaded; the page opens it.
  loaded(m) {
    if (m.source !== this.loading) return;
    Object.assign(this, { loading: null, opening: m.source });
    this.showProgress({ stage: 'done', fraction: 1 });
    this.$('pacs-cancel').hidden = true;
    this.say('Loaded; building the mesh and opening a session ...', 'info', 'opening');
    this.openVolume(m.volume);
  }

  // The viewer opened a volume (app.js 'opened').
  opened(volume) {
    if (!this.opening || volume?.source !== this.opening) return;
    this.opening = null;
    this.hideProgress();
    this.say('Opened in the viewer.', 'info', 'opened');
  }

  // m: a pacs_error {action, code, message} (export errors are the Export
  // button's).
  failed(m) {
    this.lastError = m;
    if (m.action === 'open') {
      if (m.source !== this.loading) return;
      this.loading = null;
      this.hideProgress();
    }
    if (m.action === 'endpoints') this.showEndpoints({ endpoints: [], message: m.message });
    this.say(m.message, 'error', 'error');
  }

  // The viewer could not open the loaded series (an error message of the
  // page's own open).
  viewerFailed(message) {
    if (!this.opening) return;
    this.opening = null;
    this.hideProgress();
    this.say(message, 'error', 'error');
  }

  // The load under way stops (the server stops retrieving); the gateway
  // answers with a CANCELLED pacs_error.
  cancelLoad() {
    if (this.loading) this.send({ type: 'pacs_cancel' });
  }

  // The page opens something else: a load of this panel's is dropped.
  forget() {
    this.cancelLoad();
    this.opening = null;
  }
}
