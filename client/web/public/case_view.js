// A case's kept view on the page's controls (docs/CASES.md): the gateway
// opens a case afresh with the view the case keeps (preset or MIP, crop box,
// clip planes, view cut, slices; world LPS, mm) and sends it in
// opened.view (lib/render_settings.js pageView); the page sets its controls
// to it, so that what it sends next goes on from the case's view. Nothing
// is sent here: the stream already started with the view.

// The Render select's value for a view: the page's options name mode and
// preset ('dvr:ct-bone'; 'dvr:auto', the server's choice by the image, for
// none); its MIP is 'mip:ct-vessels'; a transfer function
// of the case's own is the tab's upload ('dvr:uploaded').
export function renderValue(view) {
  if (view.mode === 'mip') return 'mip:ct-vessels';
  if (view.render_tf) return 'dvr:uploaded';
  return `dvr:${view.preset || 'auto'}`;
}

// controls: {render (select), viewCut (checkbox), slicesBox (checkbox),
// windowWidth, windowLevel, sliceOverlay (inputs), cuts (CutControls),
// slices (SliceViews)}. A preset the select does not list leaves it as it
// was (the stream still renders the case's).
export function applyCaseView(view, controls) {
  const value = renderValue(view);
  if ([...controls.render.options].some((o) => o.value === value)) controls.render.value = value;
  controls.viewCut.checked = Boolean(view.view_cut);
  controls.cuts.applyView(view.crop ?? null, view.clip ?? []);
  controls.slices.applyView(view.slices ?? []);
  controls.slicesBox.checked = controls.slices.enabled;
  const shown = controls.slices.shownWindow();
  controls.windowWidth.value = String(shown.width);
  controls.windowLevel.value = String(shown.level);
  controls.sliceOverlay.checked = controls.slices.overlay;
}
