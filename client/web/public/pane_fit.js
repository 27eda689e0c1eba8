// Canvases sized to their panes: a canvas keeps its image's aspect and is
// drawn as large as its pane allows (CSS pixels), centred; the 3D frame
// asked of the server takes the pane's aspect, so it fills the pane. The
// canvas's CSS box is the image itself (no letterbox inside it), so a
// pointer's frame pixel is (client - box corner) * frame size / box size.

const kMinSidePx = 32;  // frame pixels: a pane squeezed to nothing still asks for a frame

// The largest size (CSS px) of an imageWidth x imageHeight image inside a
// boxWidth x boxHeight box, aspect kept: {width, height}.
export function fitContain(boxWidth, boxHeight, imageWidth, imageHeight) {
  if (!(boxWidth > 0 && boxHeight > 0 && imageWidth > 0 && imageHeight > 0)) {
    return { width: 0, height: 0 };
  }
  const scale = Math.min(boxWidth / imageWidth, boxHeight / imageHeight);
  return { width: imageWidth * scale, height: imageHeight * scale };
}

// The frame size (pixels) for a pane of paneWidth x paneHeight CSS px: the
// pane's aspect, its longer side longSidePx (the page's Frame setting),
// each side at least kMinSidePx. {width, height}, integers.
export function frameSizeForPane(paneWidth, paneHeight, longSidePx) {
  const long = Math.max(kMinSidePx, Math.round(longSidePx));
  if (!(paneWidth > 0 && paneHeight > 0)) return { width: long, height: long };
  const short = (side) => Math.max(kMinSidePx, Math.round((long * side) / Math.max(paneWidth,
                                                                                   paneHeight)));
  return paneWidth >= paneHeight ? { width: long, height: short(paneHeight) }
                                 : { width: short(paneWidth), height: long };
}

// Sizes `canvas` (CSS) to fit its parent `box`, keeping canvas.width x
// canvas.height's aspect. Returns the CSS size set.
export function fitCanvas(canvas, box) {
  const size = fitContain(box.clientWidth, box.clientHeight, canvas.width, canvas.height);
  canvas.style.width = `${Math.floor(size.width)}px`;
  canvas.style.height = `${Math.floor(size.height)}px`;
  return size;
}
