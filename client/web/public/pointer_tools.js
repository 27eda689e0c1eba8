// Mouse and wheel input on the frame canvas, turned into vpm events:
//   orbit tool: drag turns the camera (azimuth, elevation), wheel zooms;
//   grab tool:  press grabs the pixel (Grab{pick}: the server casts the same
//               ray), moving drags (Drag offsets in mm from the screen motion
//               and the camera), releasing lets go (Release);
//   pin tool:   a click holds the tissue under the pixel still (Pin{pick});
//   refine tool: a click refines the mesh at the picked point;
//   crop tool:  pressing on a face of the crop box and dragging moves the
//               face along its normal (onCropPress, onCropDrag); pressing
//               off the box orbits;
//   any tool:   right or middle drag pans (Camera.pan_mm: the picture
//               follows the pointer), the wheel zooms about the pointer
//               (the point under it stays), Shift+click puts the slices
//               through the clicked point (onSlicesAt; the orbit-centre
//               plane's point, as refine-here picks). No context menu.
// Camera and drag events are sent at most once per animation frame (the
// server coalesces them too); the last one is flushed on release.
const kOrbitDegPerPixel = 0.4;   // canvas pixels of the frame's full size
const kZoomPerWheelUnit = 0.0015;

export class PointerTools {
  // canvas: the frame canvas (its width/height are the frame's full size);
  // camera(): the OrbitCamera or null; send(event) -> sequence;
  // onRefine(point_mm); onGrab(point_mm | null); onRefused(text);
  // onCropPress(x, y, width, height) -> true when on a face;
  // onCropDrag(dx, dy, width, height): frame pixels from the press.
  // keepDrags(): whether a release keeps the drag (Shift on release keeps too).
  // onSlicesAt(point_mm): Shift+click, world LPS mm.
  constructor({ canvas, camera, send, onRefine, onGrab, onRefused, onCropPress, onCropDrag,
                keepDrags = () => false, onSlicesAt = () => {} }) {
    Object.assign(this, { canvas, camera, send, onRefine, onGrab, onRefused, onCropPress,
                          onCropDrag, keepDrags, onSlicesAt });
    this.tool = 'orbit';
    this.gesture = null;  // {kind, startX, startY, lastX, lastY}
    this.queued = null;   // the newest camera or drag event waiting for a frame
    this.frameRequested = false;
    canvas.addEventListener('pointerdown', (e) => this.down(e));
    canvas.addEventListener('pointermove', (e) => this.move(e));
    canvas.addEventListener('pointerup', (e) => this.up(e));
    canvas.addEventListener('pointercancel', (e) => this.up(e));
    canvas.addEventListener('wheel', (e) => this.wheel(e), { passive: false });
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  }

  // Frame position under a pointer event, fractional (pixel centres at +0.5).
  position(e) {
    const r = this.canvas.getBoundingClientRect();
    return [((e.clientX - r.left) * this.canvas.width) / r.width,
            ((e.clientY - r.top) * this.canvas.height) / r.height];
  }

  // Frame pixel under a pointer event (row 0 at the top).
  pixel(e) {
    const r = this.canvas.getBoundingClientRect();
    const x = Math.floor(((e.clientX - r.left) * this.canvas.width) / r.width);
    const y = Math.floor(((e.clientY - r.top) * this.canvas.height) / r.height);
    return [Math.min(this.canvas.width - 1, Math.max(0, x)),
            Math.min(this.canvas.height - 1, Math.max(0, y))];
  }

  down(e) {
    const camera = this.camera();
    if (!camera || this.gesture) return;
    const [x, y] = this.pixel(e);
    const { width, height } = this.canvas;
    if (e.button === 1 || e.button === 2) {
      e.preventDefault();  // middle: no autoscroll
      this.canvas.setPointerCapture(e.pointerId);
      this.gesture = { kind: 'pan', startX: x, startY: y, lastX: x, lastY: y };
      return;
    }
    if (e.button !== 0) return;
    if (e.shiftKey && this.tool === 'orbit') {
      const point = camera.pickPointMm(x, y, width, height);
      if (camera.insideVolume(point)) {
        const world = camera.worldPoint(point);
        this.onSlicesAt({ x: world[0], y: world[1], z: world[2] });
      }
      return;
    }
    if (this.tool === 'refine' || this.tool === 'grab' || this.tool === 'pin') {
      const point = camera.pickPointMm(x, y, width, height);
      if (!camera.insideVolume(point)) {
        this.onRefused('That pixel picks a point outside the volume; aim at the volume.');
        return;
      }
      const world = camera.worldPoint(point);  // the API's frame, LPS mm
      if (this.tool === 'refine') {
        this.onRefine({ x: world[0], y: world[1], z: world[2] });
        return;
      }
      if (this.tool === 'pin') {
        this.send({ pin: { pick: true, pixel_x: x, pixel_y: y } });
        return;
      }
      this.send({ grab: { pick: true, pixel_x: x, pixel_y: y } });
      this.onGrab({ x: world[0], y: world[1], z: world[2] });  // until the server says where
    }
    let kind = this.tool;
    if (kind === 'crop') kind = this.onCropPress(x, y, width, height) ? 'crop' : 'orbit';
    this.canvas.setPointerCapture(e.pointerId);
    this.gesture = { kind, startX: x, startY: y, lastX: x, lastY: y };
  }

  move(e) {
    const g = this.gesture;
    const camera = this.camera();
    if (!g || !camera) return;
    const [x, y] = this.pixel(e);
    if (g.kind === 'orbit') {
      camera.orbit(-(x - g.lastX) * kOrbitDegPerPixel, (y - g.lastY) * kOrbitDegPerPixel);
      this.queue({ camera: camera.toProto() });
    } else if (g.kind === 'pan') {
      camera.panByPixels(x - g.lastX, y - g.lastY, this.canvas.width, this.canvas.height);
      this.queue({ camera: camera.toProto() });
    } else if (g.kind === 'crop') {
      this.onCropDrag(x - g.startX, y - g.startY, this.canvas.width, this.canvas.height);
    } else {
      const [dx, dy] = [x - g.startX, y - g.startY];
      const o = camera.dragOffsetMm(dx, dy, this.canvas.width, this.canvas.height);
      this.queue({ drag: { offset_mm: { x: o[0], y: o[1], z: o[2] } } });
    }
    [g.lastX, g.lastY] = [x, y];
  }

  up(e) {
    const g = this.gesture;
    if (!g) return;
    this.gesture = null;
    if (this.canvas.hasPointerCapture(e.pointerId)) this.canvas.releasePointerCapture(e.pointerId);
    this.flush();
    if (g.kind === 'grab') this.send({ release: { keep: Boolean(e.shiftKey || this.keepDrags()) } });
  }

  // The server reported that the grab failed: forget the gesture.
  cancelGrab() {
    if (this.gesture?.kind === 'grab') this.gesture = null;
    if (this.queued?.drag) this.queued = null;
  }

  wheel(e) {
    const camera = this.camera();
    if (!camera) return;
    e.preventDefault();
    const [x, y] = this.position(e);
    camera.zoomAbout(Math.exp(-e.deltaY * kZoomPerWheelUnit), x - 0.5, y - 0.5,
                     this.canvas.width, this.canvas.height);
    this.queue({ camera: camera.toProto() });
  }

  queue(event) {
    this.queued = event;
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(() => {
      this.frameRequested = false;
      this.flush();
    });
  }

  flush() {
    if (!this.queued) return;
    const event = this.queued;
    this.queued = null;
    this.send(event);
  }
}
