// A case's kept view in the page (docs/CASES.md): CaseInfo.view as the
// gateway reads it (lib/render_settings.js pageView: proto-loader's shape
// in the page's names), the page's settings with it (withCaseView: the
// frame size, overlay and encoding stay the page's), and the controls set
// to it (public/case_view.js applyCaseView on CutControls and SliceViews),
// so that what the page sends next is the case's view: crop, clips, slices.
// Usage: node --test case_view.test.mjs
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const load = (file) => import(pathToFileURL(path.join(here, '../../client/web', file)).href);
const { pageView, withCaseView, toProtoSettings } = await load('lib/render_settings.js');
const { applyCaseView, renderValue } = await load('public/case_view.js');
const { CutControls } = await load('public/cut_controls.js');
const { SliceViews } = await load('public/slice_views.js');

// CaseInfo.view as proto-loader hands it over (defaults: true, oneofs: true).
const kStored = {
  mode: 'RENDER_MODE_DVR', preset: 'ct-bone', width: 0, height: 0, overlay: false,
  encoding: 'ENCODING_JPEG', jpeg_quality: 0, render_tf: null, mip_window: null,
  crop: { lo_mm: { x: -10, y: -20.125, z: -30 }, hi_mm: { x: 10, y: 20, z: 30.5 } },
  clip: [{ normal: { x: 1, y: 0, z: 0 }, offset_mm: 2.5 },
         { normal: { x: 0.6, y: 0.8, z: 0 }, offset_mm: -3 }],
  view_cut: false,
  slices: [
    { orientation: 'SLICE_ORIENTATION_AXIAL', at_mm: 12.5, _at_mm: 'at_mm', at_landmark: '',
      point_lps_mm: null, normal: null, window: { width: 300, level: 50 }, pixel_mm: 0,
      overlay: true, view: 'axial' },
    { orientation: 'SLICE_ORIENTATION_CORONAL', at_landmark: '',
      point_lps_mm: { x: 1, y: 2, z: 3 }, normal: null, window: null, pixel_mm: 0,
      overlay: false, view: 'coronal' }],
};

const element = (props = {}) => ({ value: '', checked: false, textContent: '', hidden: false,
                                   disabled: false, addEventListener() {}, ...props });

function controls() {
  const cuts = new CutControls({
    crop: element(), cropLo: [element(), element(), element()],
    cropHi: [element(), element(), element()], clipSide: element(), clipAt: element(),
    clipLabel: element(), clipAdd: element(), clipKept: element(), clipClear: element(),
  }, () => assert.fail('applying a view sends nothing'));
  cuts.setVolume({ dims: [48, 48, 48], spacing_mm: { x: 1, y: 1, z: 1 },
                   origin_lps_mm: { x: -24, y: -24, z: -24 } });
  const canvases = { axial: element(), coronal: element(), sagittal: element() };
  const slices = new SliceViews({ canvases, labels: canvases, tool: () => 'orbit',
                                  send: () => assert.fail('applying a view sends nothing'),
                                  onChange: () => assert.fail('applying a view sends nothing') });
  const options = ['dvr:ct-soft-tissue', 'dvr:ct-bone', 'mip:ct-vessels']
    .map((value) => ({ value }));
  return { render: { options, value: 'dvr:ct-soft-tissue' }, viewCut: element({ checked: true }),
           slicesBox: element(), windowWidth: element(), windowLevel: element(),
           sliceOverlay: element(), cuts, slices };
}

test('CaseView_ReadsTheStoredViewInThePagesNames', () => {
  const view = pageView(kStored);
  assert.deepEqual([view.mode, view.preset, view.view_cut], ['dvr', 'ct-bone', false]);
  assert.deepEqual(view.crop, kStored.crop);
  assert.deepEqual(view.clip, kStored.clip);
  assert.deepEqual(view.slices[0], { orientation: 'SLICE_ORIENTATION_AXIAL', at_mm: 12.5,
                                     window: { width: 300, level: 50 }, pixel_mm: 0,
                                     overlay: true, view: 'axial' });
  assert.equal(view.slices[1].at_mm, undefined, 'an at_mm never set stays unset');
  assert.deepEqual(view.slices[1].point_lps_mm, { x: 1, y: 2, z: 3 });
  for (const key of ['width', 'height', 'encoding', 'overlay', 'render_tf', 'mip_window']) {
    assert.equal(view[key], undefined, key);
  }
  assert.equal(pageView(null), null);
  assert.equal(pageView({ ...kStored, mode: 'RENDER_MODE_MIP' }).mode, 'mip');
});

test('CaseView_ReplacesThePagesViewAndKeepsItsFrame', () => {
  const page = { mode: 'mip', preset: 'ct-vessels', width: 256, height: 256, overlay: true,
                 encoding: 'png', view_cut: true, crop: { lo_mm: {}, hi_mm: {} }, uploaded_tf: true,
                 slices: [{ view: 'sagittal' }] };
  const merged = withCaseView(page, pageView(kStored));
  assert.deepEqual([merged.mode, merged.preset, merged.width, merged.height, merged.overlay,
                    merged.encoding, merged.view_cut, merged.uploaded_tf],
                   ['dvr', 'ct-bone', 256, 256, true, 'png', false, undefined]);
  assert.deepEqual(merged.crop, kStored.crop);
  assert.deepEqual(merged.slices.map((s) => s.view), ['axial', 'coronal']);
  const proto = toProtoSettings(merged);
  assert.equal(proto.mode, 'RENDER_MODE_DVR');
  // A view without a crop takes the page's crop away.
  assert.equal(withCaseView(page, pageView({ ...kStored, crop: null })).crop, undefined);
  // A transfer function of the case's own: the tab's upload renders it.
  const tf = { name: 'liver', colors: [], opacities: [] };
  const withTf = withCaseView(page, pageView({ ...kStored, preset: '', render_tf: tf }));
  assert.deepEqual([withTf.uploaded_tf, withTf.render_tf, withTf.preset],
                   [true, undefined, undefined]);
});

test('CaseView_SetsThePagesControlsSoThatTheyShowAndSendTheView', () => {
  const c = controls();
  const view = pageView(kStored);
  applyCaseView(view, c);
  assert.equal(c.render.value, 'dvr:ct-bone');
  assert.equal(c.viewCut.checked, false);
  // The crop box exactly (not rounded to the fields' 0.1 mm), the planes kept.
  assert.deepEqual(c.cuts.settings(), { crop: kStored.crop, clip: kStored.clip });
  assert.match(c.cuts.e.clipKept.textContent,
               /left of 2\.5; plane \(0\.60, 0\.80, 0\.00\) at -3\.0/);
  // The slice panes on, the axial plane where it was, window and overlay.
  assert.equal(c.slicesBox.checked, true);
  assert.deepEqual([c.windowWidth.value, c.windowLevel.value, c.sliceOverlay.checked],
                   ['300', '50', true]);
  const specs = c.slices.specs();
  assert.equal(specs.find((s) => s.view === 'axial').at_mm, 12.5);
  assert.equal(specs.find((s) => s.view === 'coronal').at_mm, undefined);
  // MIP, and a preset the select does not list (it stays as it was).
  assert.equal(renderValue({ mode: 'mip' }), 'mip:ct-vessels');
  const d = controls();
  applyCaseView({ ...view, preset: 'CT-AAA', crop: undefined, clip: [], slices: [] }, d);
  assert.equal(d.render.value, 'dvr:ct-soft-tissue');
  assert.deepEqual(d.cuts.settings(), {});
  assert.equal(d.slicesBox.checked, false);
});

test('SliceViews_SendNoWindowUntilTheUserSetsOneAndShowTheServers', () => {
  const { slices } = controls();
  slices.enabled = true;
  // At start the server picks the window for the volume (soft tissue on CT,
  // percentiles on an MRI): no slice asks for one.
  assert.ok(slices.specs().every((s) => s.window === undefined));
  assert.deepEqual(slices.shownWindow(), { width: 400, level: 40 }, 'before any frame');
  // A frame's slice geometry reports the window the server used.
  slices.geometry.axial = { window: { width: 1210, level: 480 } };
  assert.deepEqual(slices.shownWindow(), { width: 1210, level: 480 });
  // The user's window is sent, and shown, until a new volume.
  slices.window = { width: 350, level: 60 };
  assert.ok(slices.specs().every((s) => s.window.width === 350 && s.window.level === 60));
  assert.deepEqual(slices.shownWindow(), { width: 350, level: 60 });
  slices.reset();
  assert.ok(slices.specs().every((s) => s.window === undefined));
});
