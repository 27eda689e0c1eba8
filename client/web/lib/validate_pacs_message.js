// The PACS messages a browser tab may send (docs/WEB.md, "Studies"),
// checked before the gateway calls vpm-server: endpoint names as the
// server's --pacs file allows them, query values bounded as the server bounds
// them (64 UTF-8 bytes, no control characters; dates YYYYMMDD or a range
// FROM-TO with either end open; a modality code), DICOM UIDs and pacs:
// sources. A refused field is named, never quoted: it may hold a patient's
// name or ID, which the gateway neither logs nor echoes.
//
//   {type: 'pacs_endpoints'}
//   {type: 'pacs_search', endpoint, patient_name, patient_id, patient_birth_date,
//    study_date, modality, accession_number, limit}   (all but endpoint optional)
//   {type: 'pacs_series', endpoint, study_uid}
//   {type: 'pacs_open', source}                        pacs:ENDPOINT/STUDY_UID/SERIES_UID
//   {type: 'pacs_cancel'}                              the load under way
//   {type: 'pacs_thumbnail', endpoint, study_uid, series_uid}
//   {type: 'export_dicom', endpoint, series_description}  (description optional)
import { isDicomUid, isPacsEndpoint, parsePacsSource } from '../public/pacs_source.js';

export const kMaxPacsQueryBytes = 64;
export const kMaxExportDescriptionChars = 64;  // ExportDicomRequest.series_description
const kMaxStudies = 1000;                      // SearchStudiesRequest.limit
const kControl = /[\u0000-\u001f\u007f]/;
const kDateOrRange = /^(\d{8}|\d{8}-|-\d{8}|\d{8}-\d{8})$/;
const kModality = /^[A-Za-z0-9_]{1,16}$/;
const kSearchKeys = ['type', 'endpoint', 'patient_name', 'patient_id', 'patient_birth_date',
                     'study_date', 'modality', 'accession_number', 'limit'];

function endpoint(message) {
  if (!isPacsEndpoint(message.endpoint)) {
    throw new Error('endpoint: a PACS endpoint name (1 to 64 letters, digits, . _ -)');
  }
}

// An optional query value: a string of at most kMaxPacsQueryBytes bytes
// without control characters ('' or absent: not searched on).
function queryValue(message, key) {
  const v = message[key];
  if (v === undefined) return;
  if (typeof v !== 'string' || Buffer.byteLength(v, 'utf8') > kMaxPacsQueryBytes || kControl.test(v)) {
    throw new Error(`${key}: a string of at most ${kMaxPacsQueryBytes} bytes without control ` +
                    'characters');
  }
}

function dateValue(message, key) {
  queryValue(message, key);
  const v = message[key];
  if (v && !kDateOrRange.test(v)) {
    throw new Error(`${key}: YYYYMMDD, or a range FROM-TO with either end open`);
  }
}

function checkSearch(message) {
  const unknown = Object.keys(message).find((k) => !kSearchKeys.includes(k));
  if (unknown !== undefined) throw new Error(`pacs_search: no field '${unknown.slice(0, 32)}'`);
  endpoint(message);
  for (const key of ['patient_name', 'patient_id', 'accession_number']) queryValue(message, key);
  for (const key of ['patient_birth_date', 'study_date']) dateValue(message, key);
  queryValue(message, 'modality');
  if (message.modality && !kModality.test(message.modality)) {
    throw new Error('modality: a modality code (1 to 16 letters, digits, _)');
  }
  const { limit } = message;
  if (limit !== undefined && !(Number.isInteger(limit) && limit >= 1 && limit <= kMaxStudies)) {
    throw new Error(`limit: an integer from 1 to ${kMaxStudies}`);
  }
}

function checkExport(message) {
  endpoint(message);
  const d = message.series_description;
  if (d !== undefined && (typeof d !== 'string' || d.length > kMaxExportDescriptionChars ||
                          kControl.test(d))) {
    throw new Error(`series_description: a string of at most ${kMaxExportDescriptionChars} ` +
                    'characters without control characters');
  }
}

// Returns the message, or null when its type is not a PACS message.
export function parsePacsMessage(message) {
  switch (message.type) {
    case 'pacs_endpoints':
    case 'pacs_cancel':
      return message;
    case 'pacs_search':
      checkSearch(message);
      return message;
    case 'pacs_series':
      endpoint(message);
      if (!isDicomUid(message.study_uid)) {
        throw new Error('study_uid: a DICOM UID (digits and dots, at most 64 characters)');
      }
      return message;
    case 'pacs_thumbnail': {
      const unknown = Object.keys(message).find(
        (k) => !['type', 'endpoint', 'study_uid', 'series_uid'].includes(k));
      if (unknown !== undefined) throw new Error(`pacs_thumbnail: no field '${unknown.slice(0, 32)}'`);
      endpoint(message);
      for (const key of ['study_uid', 'series_uid']) {
        if (!isDicomUid(message[key])) {
          throw new Error(`${key}: a DICOM UID (digits and dots, at most 64 characters)`);
        }
      }
      return message;
    }
    case 'pacs_open':
      if (typeof message.source !== 'string' || message.source.length > 300 ||
          !parsePacsSource(message.source)) {
        throw new Error('source: pacs:ENDPOINT/STUDY_UID/SERIES_UID[?stack=N]');
      }
      return message;
    case 'export_dicom':
      checkExport(message);
      return message;
    default:
      return null;
  }
}
