// The messages a browser tab may send the gateway, checked before anything
// acts on them: a JSON object with a known `type` and fields of the right
// types (events against the proto's ClientEvent, proto_shape.js; the PACS
// messages in validate_pacs_message.js). Throws an Error with a message for
// the page.
import { toProtoSettings } from './render_settings.js';
import { parseDataRootMessage } from './data_root_calls.js';
import { parsePacsMessage } from './validate_pacs_message.js';

const kEventKinds = ['camera', 'settings', 'grab', 'drag', 'pull', 'release', 'pin', 'reset'];
const kMaxIdChars = 128;
const kMaxSourceChars = 2048;
const kMaxSlices = 3;
// A transfer-function file's text travels in one WebSocket message (ws
// accepts 64 KiB): one exported preset, not ParaView's whole list.
export const kMaxTfTextChars = 60000;
const kMaxTfNameChars = 256;
// Case ids are the server's (case-HEX); a title is at most 256 bytes
// (UpdateCaseRequest), checked here in UTF-8 bytes as the server counts.
const kCaseIdPattern = /^[A-Za-z0-9][A-Za-z0-9._:-]{0,127}$/;
export const kMaxCaseTitleBytes = 256;
// A Slicer .vp holds numbers only, each far shorter than this: a longer
// field is refused here, before the server reads (and quotes) it.
export const kMaxVpFieldChars = 64;

function optionalString(message, key, max) {
  const v = message[key];
  if (v === undefined) return;
  if (typeof v !== 'string' || v.length === 0 || v.length > max) {
    throw new Error(`${key}: a string of 1 to ${max} characters`);
  }
}

function vec3(shape, value, path) {
  shape.check('Vec3', value, path);
  for (const axis of ['x', 'y', 'z']) {
    if (typeof value[axis] !== 'number') throw new Error(`${path}.${axis}: required`);
  }
}

// The page's settings (mode 'dvr' | 'mip', encoding 'jpeg' | 'png') as the
// proto's RenderSettings; throws when they are not.
export function checkSettings(shape, settings, path) {
  if (settings === undefined) return;
  if (settings === null || typeof settings !== 'object' || Array.isArray(settings)) {
    throw new Error(`${path}: an object`);
  }
  for (const [key, names] of [['mode', ['dvr', 'mip']], ['encoding', ['jpeg', 'png']]]) {
    if (settings[key] !== undefined && !names.includes(settings[key])) {
      throw new Error(`${path}.${key}: one of ${names.join(', ')}`);
    }
  }
  if (settings.uploaded_tf !== undefined && typeof settings.uploaded_tf !== 'boolean') {
    throw new Error(`${path}.uploaded_tf: true or false`);
  }
  if (Array.isArray(settings.slices) && settings.slices.length > kMaxSlices) {
    throw new Error(`${path}.slices: at most ${kMaxSlices}`);
  }
  shape.check('RenderSettings', toProtoSettings(settings), path);
}

// Throws when a field of a Slicer .vp's text is longer than any number.
function checkVpFields(text) {
  const lines = text.split('\n');
  for (let i = 0; i < lines.length; ++i) {
    const long = lines[i].split(/\s+/).find((field) => field.length > kMaxVpFieldChars);
    if (long !== undefined) {
      throw new Error(`tf: line ${i + 1} of the .vp has a field of ${long.length} characters; ` +
                      `its fields are numbers (at most ${kMaxVpFieldChars} characters)`);
    }
  }
}

// message.sequence (optional): the page's last event sequence, carried by
// an open so that the new stream's frames report it as shown.
function optionalSequence(message) {
  const v = message.sequence;
  if (v !== undefined && !(Number.isSafeInteger(v) && v >= 0)) {
    throw new Error('sequence: an integer from 0');
  }
}

// message[key]: a case id (required).
function caseId(message, key = 'case_id') {
  const v = message[key];
  if (typeof v !== 'string' || !kCaseIdPattern.test(v)) {
    throw new Error(`${key}: a case id (letters, digits, . _ : -; 1 to 128 characters)`);
  }
}

// The case messages (docs/WEB.md, "Cases"): returns the message, or null
// when its type is not one of them.
function parseCaseMessage(shape, message) {
  switch (message.type) {
    case 'cases':
      return message;
    case 'open_case':
      caseId(message);
      optionalSequence(message);
      checkSettings(shape, message.settings, 'settings');
      if (message.camera !== undefined && message.camera !== null) {
        shape.check('Camera', message.camera, 'camera');
      }
      return message;
    case 'rename_case': {
      caseId(message);
      const { title } = message;
      if (typeof title !== 'string' || title.trim() === '' ||
          Buffer.byteLength(title, 'utf8') > kMaxCaseTitleBytes || /[\u0000-\u001f\u007f]/.test(title)) {
        throw new Error(`title: a string of 1 to ${kMaxCaseTitleBytes} bytes without control ` +
                        'characters');
      }
      return message;
    }
    case 'delete_case':
      caseId(message);
      return message;
    case 'undo':
      if (message.redo !== undefined && typeof message.redo !== 'boolean') {
        throw new Error('redo: true or false');
      }
      return message;
    default:
      return null;
  }
}

// data: the WebSocket message (Buffer); isBinary: its opcode. Returns the
// parsed message.
export function parseMessage(shape, data, isBinary) {
  if (isBinary) throw new Error('binary messages are not accepted');
  let message;
  try {
    message = JSON.parse(data.toString('utf8'));
  } catch (e) {
    throw new Error(`not JSON (${e.message})`);
  }
  if (message === null || typeof message !== 'object' || Array.isArray(message)) {
    throw new Error('a message is a JSON object with a "type"');
  }
  switch (message.type) {
    case 'list':
      return message;
    case 'open':
      optionalString(message, 'source', kMaxSourceChars);
      optionalString(message, 'volume_id', kMaxIdChars);
      if ((message.source === undefined) === (message.volume_id === undefined)) {
        throw new Error('open: give one of source and volume_id');
      }
      optionalSequence(message);
      checkSettings(shape, message.settings, 'settings');
      if (message.camera !== undefined && message.camera !== null) {
        shape.check('Camera', message.camera, 'camera');
      }
      return message;
    case 'watch':
      optionalString(message, 'session_id', kMaxIdChars);
      if (message.session_id === undefined) throw new Error('watch: session_id required');
      checkSettings(shape, message.settings, 'settings');
      return message;
    case 'event': {
      const { event } = message;
      if (event === null || typeof event !== 'object' || Array.isArray(event)) {
        throw new Error('event: an object');
      }
      const kinds = kEventKinds.filter((k) => event[k] !== undefined);
      if (kinds.length !== 1) {
        throw new Error(`event: exactly one of ${kEventKinds.join(', ')} (got ${kinds.length})`);
      }
      checkSettings(shape, event.settings, 'event.settings');
      shape.check('ClientEvent', { ...event, settings: undefined }, 'event');
      return message;
    }
    case 'refine':
      vec3(shape, message.point_mm, 'point_mm');
      return message;
    case 'tf': {
      optionalString(message, 'file_name', kMaxTfNameChars);
      optionalString(message, 'preset', kMaxTfNameChars);
      if (message.file_name === undefined || !/\.(json|vp)$/.test(message.file_name)) {
        throw new Error('tf: file_name ending in .json (ParaView) or .vp (3D Slicer) required');
      }
      if (typeof message.text !== 'string' || message.text.length > kMaxTfTextChars) {
        throw new Error(`tf: text, the file's contents, at most ${kMaxTfTextChars} characters`);
      }
      if (message.file_name.endsWith('.vp')) checkVpFields(message.text);
      return message;
    }
    default: {
      const known = parseCaseMessage(shape, message) ?? parsePacsMessage(message) ??
                    parseDataRootMessage(message);
      if (known) return known;
      throw new Error(`unknown message type '${String(message.type).slice(0, 32)}'`);
    }
  }
}
