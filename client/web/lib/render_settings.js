// The page speaks in the names a user reads (mode 'dvr' | 'mip', encoding
// 'jpeg' | 'png'); vpm.v3 carries them as enums. proto-loader is set up with
// `enums: String`, so an enum travels as its value's name.
const kModes = { dvr: 'RENDER_MODE_DVR', mip: 'RENDER_MODE_MIP' };
const kEncodings = { jpeg: 'ENCODING_JPEG', png: 'ENCODING_PNG' };
// A value outside the enum: the server refuses it with INVALID_ARGUMENT,
// naming the field, as it refused an unknown name before.
const kUnknown = 999;

// The page's settings object as a vpm.v3.RenderSettings. `uploaded_tf:
// true` asks for the transfer function this tab uploaded (`uploadedTf`, a
// RenderTransferFunction the gateway holds: too large to travel with every
// settings message) in place of the preset.
export function toProtoSettings(settings, uploadedTf = null) {
  if (!settings || typeof settings !== 'object') return {};
  const out = { ...settings };
  delete out.uploaded_tf;
  if (settings.mode !== undefined) out.mode = kModes[settings.mode] ?? kUnknown;
  if (settings.encoding !== undefined) out.encoding = kEncodings[settings.encoding] ?? kUnknown;
  if (settings.uploaded_tf === true && uploadedTf) {
    out.render_tf = uploadedTf;
    delete out.preset;
  }
  return out;
}

// A frame's encoding as the page names it.
export function encodingName(encoding) {
  return encoding === 'ENCODING_PNG' ? 'png' : 'jpeg';
}
