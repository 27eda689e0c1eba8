// The slice window presets (CT, Hounsfield units): width W and level L of
// SliceSpec.window. Keys 1 to 4 pick them in this order (view_keys.js).
export const kWindowPresets = [
  { name: 'soft-tissue', label: 'Soft tissue', width: 400, level: 40 },
  { name: 'bone', label: 'Bone', width: 1800, level: 400 },
  { name: 'lung', label: 'Lung', width: 1500, level: -600 },
  { name: 'brain', label: 'Brain', width: 80, level: 40 },
];

// The preset named `name`, or null.
export function windowPreset(name) {
  return kWindowPresets.find((p) => p.name === name) ?? null;
}

// The name of the preset with this window ({width, level}, HU), or '' (a
// window of the user's own).
export function presetNameOf(window) {
  if (!window) return '';
  const p = kWindowPresets.find((q) => q.width === window.width && q.level === window.level);
  return p ? p.name : '';
}
