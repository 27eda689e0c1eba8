// The Studies panel's search form as a `pacs_search` message
// (SearchStudiesRequest, docs/PACS.md): empty fields are left out, dates go
// as DICOM dates (YYYYMMDD; a date input's YYYY-MM-DD is accepted) and the
// study date as a range FROM-TO with either end open. Throws an Error whose
// message names the field, never its value (a patient's name or ID).

// Each query value is at most this many UTF-8 bytes (the server refuses
// longer ones with INVALID_ARGUMENT).
export const kMaxQueryBytes = 64;
export const kMaxStudies = 1000;  // SearchStudiesRequest.limit
const kDicomDate = /^\d{8}$/;

// value: '', 'YYYYMMDD' or 'YYYY-MM-DD'. Returns '' or 'YYYYMMDD'.
export function dicomDate(value, field) {
  const v = String(value ?? '').trim().replaceAll('-', '');
  if (v !== '' && !kDicomDate.test(v)) throw new Error(`${field}: a date, YYYYMMDD or YYYY-MM-DD`);
  return v;
}

// A DICOM date range: '' (any), 'FROM-' (from), '-TO' (up to), 'FROM-TO',
// or the one day 'D' when both ends are that day.
export function dateRange(from, to, field) {
  const [a, b] = [dicomDate(from, `${field} from`), dicomDate(to, `${field} to`)];
  if (!a && !b) return '';
  if (a && b && a > b) throw new Error(`${field}: the first date is after the second`);
  return a === b ? a : `${a}-${b}`;
}

function queryText(value, field) {
  const v = String(value ?? '').trim();
  if (new TextEncoder().encode(v).length > kMaxQueryBytes) {
    throw new Error(`${field}: at most ${kMaxQueryBytes} bytes`);
  }
  if (/[\u0000-\u001f\u007f]/.test(v)) throw new Error(`${field}: no control characters`);
  return v;
}

// fields: {patient_name, patient_id, birth_date, study_date_from,
// study_date_to, modality, accession_number, limit}, strings as typed.
export function searchMessage(endpoint, fields) {
  if (!endpoint) throw new Error('pick a PACS endpoint first');
  const modality = queryText(fields.modality, 'modality').toUpperCase();
  if (modality && !/^[A-Z0-9_]{1,16}$/.test(modality)) {
    throw new Error('modality: a DICOM modality code such as CT or MR');
  }
  const message = {
    type: 'pacs_search',
    endpoint,
    patient_name: queryText(fields.patient_name, 'patient name'),
    patient_id: queryText(fields.patient_id, 'patient ID'),
    patient_birth_date: dicomDate(fields.birth_date, 'birth date'),
    study_date: dateRange(fields.study_date_from, fields.study_date_to, 'study date'),
    modality,
    accession_number: queryText(fields.accession_number, 'accession number'),
  };
  for (const key of Object.keys(message)) if (message[key] === '') delete message[key];
  if (fields.limit !== undefined && fields.limit !== '') {
    const limit = Number(fields.limit);
    if (!Number.isInteger(limit) || limit < 1 || limit > kMaxStudies) {
      throw new Error(`limit: 1 to ${kMaxStudies} studies`);
    }
    message.limit = limit;
  }
  return message;
}

// A DICOM person name ("Family^Given^Middle^Prefix^Suffix") as people read
// it: "Family, Given Middle".
export function personName(pn) {
  const [family = '', ...rest] = String(pn ?? '').split('=')[0].split('^');
  const given = rest.filter(Boolean).join(' ');
  return given ? `${family}, ${given}` : family;
}

// 'YYYYMMDD' as 'YYYY-MM-DD'; anything else as it is.
export function shownDate(d) {
  return kDicomDate.test(d ?? '') ? `${d.slice(0, 4)}-${d.slice(4, 6)}-${d.slice(6)}` : (d ?? '');
}
