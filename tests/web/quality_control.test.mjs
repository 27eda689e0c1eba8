// The interactive-quality choice in the page (public/quality_control.js)
// and on its way to the server (lib/render_settings.js toProtoSettings:
// the page's names as RenderSettings.interactive_quality's).
// Usage: node --test quality_control.test.mjs
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const load = (file) => import(pathToFileURL(path.join(here, '../../client/web', file)).href);
const { toProtoSettings } = await load('lib/render_settings.js');
const { QualityControl, kDefaultInteractiveQuality, kInteractiveQualities } =
  await load('public/quality_control.js');

function memoryStorage(initial = {}) {
  const items = { ...initial };
  return { getItem: (k) => items[k] ?? null, setItem: (k, v) => { items[k] = String(v); }, items };
}

test('QualityControl_StartsAtTheDefaultOrTheStoredChoice', () => {
  assert.deepEqual(new QualityControl(null, null, memoryStorage()).settings(),
                   { interactive_quality: kDefaultInteractiveQuality });
  const stored = memoryStorage({ 'vpm.interactiveQuality': 'sharp' });
  assert.equal(new QualityControl(null, null, stored).value, 'sharp');
  const junk = memoryStorage({ 'vpm.interactiveQuality': 'ultra' });
  assert.equal(new QualityControl(null, null, junk).value, kDefaultInteractiveQuality);
  assert.equal(kDefaultInteractiveQuality, 'auto');
  assert.deepEqual(kInteractiveQualities.map((q) => q.value),
                   ['auto', 'fast', 'balanced', 'sharp']);
});

test('ToProtoSettings_NamesTheInteractiveQualityAsTheProtoDoes', () => {
  // auto: UNSPECIFIED, the server's device chooses.
  assert.equal(toProtoSettings({ interactive_quality: 'auto' }).interactive_quality,
               'INTERACTIVE_QUALITY_UNSPECIFIED');
  assert.equal(toProtoSettings({ interactive_quality: 'fast' }).interactive_quality,
               'INTERACTIVE_QUALITY_FAST');
  assert.equal(toProtoSettings({ interactive_quality: 'balanced' }).interactive_quality,
               'INTERACTIVE_QUALITY_BALANCED');
  assert.equal(toProtoSettings({ interactive_quality: 'sharp' }).interactive_quality,
               'INTERACTIVE_QUALITY_SHARP');
  // Unknown: a value outside the enum, which the server refuses by name.
  assert.equal(toProtoSettings({ interactive_quality: 'ultra' }).interactive_quality, 999);
  assert.equal('interactive_quality' in toProtoSettings({ mode: 'dvr' }), false);
});
