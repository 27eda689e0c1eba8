// The page speaks in the names a user reads (mode 'dvr' | 'mip', encoding
// 'jpeg' | 'png', interactive_quality 'auto' | 'fast' | 'balanced' | 'sharp'); vpm.v3 carries them
// as enums. proto-loader is set up with `enums: String`, so an enum travels as its value's name.
const kModes = { dvr: 'RENDER_MODE_DVR', mip: 'RENDER_MODE_MIP' };
const kEncodings = { jpeg: 'ENCODING_JPEG', png: 'ENCODING_PNG' };
const kInteractiveQualities = {
  auto: 'INTERACTIVE_QUALITY_UNSPECIFIED',
  fast: 'INTERACTIVE_QUALITY_FAST',
  balanced: 'INTERACTIVE_QUALITY_BALANCED',
  sharp: 'INTERACTIVE_QUALITY_SHARP'
};
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
  if (settings.interactive_quality !== undefined) {
    out.interactive_quality = kInteractiveQualities[settings.interactive_quality] ?? kUnknown;
  }
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

// The view a case keeps (CaseInfo.view, a vpm.v3.RenderSettings as
// proto-loader gives it: enums by name, unset messages null) in the page's
// names: {mode, preset, mip_window, crop, clip, view_cut, slices} and
// render_tf when it had a transfer function of its own; null for none.
// World LPS, mm, as stored.
export function pageView(view) {
  if (!view || typeof view !== 'object') return null;
  const out = { mode: view.mode === 'RENDER_MODE_MIP' ? 'mip' : 'dvr',
                view_cut: Boolean(view.view_cut),
                clip: (view.clip ?? []).map((p) => ({ normal: p.normal, offset_mm: p.offset_mm })),
                slices: (view.slices ?? []).map(pageSlice) };
  if (view.preset) out.preset = view.preset;
  if (view.render_tf) out.render_tf = view.render_tf;
  if (view.mip_window) out.mip_window = view.mip_window;
  if (view.crop) out.crop = { lo_mm: view.crop.lo_mm, hi_mm: view.crop.hi_mm };
  return out;
}

// A SliceSpec without proto-loader's unset fields (null, '' and the
// `_at_mm` oneof marker): at_mm (proto3 optional) comes only when it was
// set, named by the marker.
function pageSlice(s) {
  const out = {};
  for (const [key, value] of Object.entries(s)) {
    if (key.startsWith('_') || value === null || value === undefined || value === '') continue;
    out[key] = value;
  }
  if ('_at_mm' in s && s._at_mm !== 'at_mm') delete out.at_mm;
  return out;
}

const kViewFields = ['mode', 'preset', 'uploaded_tf', 'render_tf', 'mip_window', 'crop', 'clip',
                     'view_cut', 'slices'];

// The page's settings with a case's view (pageView) in place of what they
// showed: the frame size, encoding and overlay stay the page's. A view with
// a transfer function of its own asks for it as the tab's upload.
export function withCaseView(settings, view) {
  const out = { ...(settings ?? {}) };
  for (const key of kViewFields) delete out[key];
  const { render_tf: renderTf, ...rest } = view;
  Object.assign(out, rest);
  if (renderTf) out.uploaded_tf = true;
  return out;
}
