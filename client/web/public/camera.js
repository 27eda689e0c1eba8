// The orbit camera of server/raycast/camera.{h,cc}, mirrored in the browser
// so that screen motion becomes millimetres: drag offsets for the grab tool,
// and the picked point for refine-here (a grab's point is the server's own,
// Frame.grab_point_mm, once its frame arrives). Physical voxel space
// (index * spacing, mm) throughout.
//
// Conventions kept from the server: azimuth 0, elevation 0 looks from
// anterior to posterior with superior up; azimuth turns towards the
// patient's left, elevation towards superior; the vertical field of view is
// 30 degrees across the shorter image side; distance 0 in the API means
// "fit the volume", which fitDistanceMm reproduces.

export const kFovDeg = 30;  // Camera::Pose::fov_deg
const kDegToRad = Math.PI / 180;

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]];
const normalize = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));

// The slopes (along right, along up, per unit forward) of the ray through
// pixel (px, py) of a width x height frame, row 0 at the top, the field of
// view kFovDeg across the shorter side (CameraRays::Direction).
function pixelSlopes(px, py, width, height) {
  const tanHalf = Math.tan(0.5 * kFovDeg * kDegToRad);
  const shorter = Math.max(1, Math.min(width, height));
  return [((2 * (px + 0.5)) / width - 1) * tanHalf * (width / shorter),
          (1 - (2 * (py + 0.5)) / height) * tanHalf * (height / shorter)];
}

export class OrbitCamera {
  // volume: a VolumeInfo as the gateway sends it (dims, spacing_mm,
  // direction: 9 values, column-major, columns the i, j, k axes in LPS).
  constructor(volume) {
    const d = volume.direction?.length === 9 ? volume.direction : [1, 0, 0, 0, 1, 0, 0, 0, 1];
    const columns = [d.slice(0, 3), d.slice(3, 6), d.slice(6, 9)];
    this.columns = columns;
    const o = volume.origin_lps_mm ?? { x: 0, y: 0, z: 0 };
    this.originLps = [o.x ?? 0, o.y ?? 0, o.z ?? 0];
    // Physical direction of world (LPS) direction w: D^T w.
    const toPhysical = (w) => normalize(columns.map((c) => dot(c, w)));
    this.anterior = toPhysical([0, -1, 0]);
    this.left = toPhysical([1, 0, 0]);
    this.superior = toPhysical([0, 0, 1]);
    this.handedness = dot(columns[0], cross(columns[1], columns[2])) < 0 ? -1 : 1;
    const spacing = volume.spacing_mm ?? { x: 1, y: 1, z: 1 };
    this.extentMm = [0, 1, 2].map((a) => (Number(volume.dims[a]) - 1) * [spacing.x, spacing.y,
                                                                           spacing.z][a]);
    this.centreMm = scale(this.extentMm, 0.5);
    this.reset();
  }

  reset() {
    this.azimuthDeg = 0;
    this.elevationDeg = 0;
    this.panMm = [0, 0];
    this.distanceMm = this.fitDistanceMm();
  }

  forward() {
    const az = this.azimuthDeg * kDegToRad, el = this.elevationDeg * kDegToRad;
    const horizontal = add(scale(this.anterior, Math.cos(az)), scale(this.left, Math.sin(az)));
    return scale(add(scale(horizontal, Math.cos(el)), scale(this.superior, Math.sin(el))), -1);
  }

  up() {
    const az = this.azimuthDeg * kDegToRad, el = this.elevationDeg * kDegToRad;
    const horizontal = add(scale(this.anterior, Math.cos(az)), scale(this.left, Math.sin(az)));
    return add(scale(horizontal, -Math.sin(el)), scale(this.superior, Math.cos(el)));
  }

  right() {
    return scale(cross(this.forward(), this.up()), this.handedness);
  }

  target() {
    return add(this.centreMm, add(scale(this.right(), this.panMm[0]), scale(this.up(), this.panMm[1])));
  }

  eye() {
    return add(this.target(), scale(this.forward(), -this.distanceMm));
  }

  // Camera::ForVolume: the smallest distance at which all eight corners of
  // the image box are in view, plus 5%. Depends on orientation only through
  // the default (azimuth 0, elevation 0) pose, as on the server.
  fitDistanceMm() {
    const saved = [this.azimuthDeg, this.elevationDeg];
    this.azimuthDeg = 0;
    this.elevationDeg = 0;
    const f = this.forward(), u = this.up(), r = this.right();
    [this.azimuthDeg, this.elevationDeg] = saved;
    const tanHalf = Math.tan(0.5 * kFovDeg * kDegToRad);
    let distance = 0;
    for (let c = 0; c < 8; ++c) {
      const corner = [c & 1 ? this.extentMm[0] : 0, c & 2 ? this.extentMm[1] : 0,
                      c & 4 ? this.extentMm[2] : 0];
      const v = add(corner, scale(this.centreMm, -1));
      const lateral = Math.max(Math.abs(dot(v, r)), Math.abs(dot(v, u)));
      distance = Math.max(distance, lateral / tanHalf - dot(v, f));
    }
    return Math.max(1.05 * distance, 1e-3);
  }

  orbit(deltaAzimuthDeg, deltaElevationDeg) {
    this.azimuthDeg = ((this.azimuthDeg + deltaAzimuthDeg + 540) % 360) - 180;
    // Kept short of the poles, where up would flip.
    this.elevationDeg = Math.max(-89, Math.min(89, this.elevationDeg + deltaElevationDeg));
  }

  // factor > 1 moves closer.
  zoom(factor) {
    const fit = this.fitDistanceMm();
    this.distanceMm = Math.max(0.05 * fit, Math.min(20 * fit, this.distanceMm / factor));
  }

  // Pans the view so the picture follows a screen motion of (dxPx right,
  // dyPx down) on a width x height frame: what lies on the orbit-centre
  // plane moves with the pointer. Camera.pan_mm is along (right, up), mm.
  panByPixels(dxPx, dyPx, width, height) {
    const s = this.mmPerPixel(width, height);
    this.panMm = [this.panMm[0] - dxPx * s, this.panMm[1] + dyPx * s];
  }

  // Zooms by `factor` (> 1 moves closer, clamped as zoom) about frame pixel
  // (px, py) of a width x height frame: the point of the orbit-centre plane
  // under that pixel stays under it (zoom moves the eye along the forward
  // axis; the pan takes the target towards the point by the distance
  // travelled times the pixel's offset from the centre). Points nearer or
  // farther than the orbit centre drift a little (perspective).
  zoomAbout(factor, px, py, width, height) {
    const before = this.distanceMm;
    this.zoom(factor);
    const travelled = before - this.distanceMm;
    const [sx, sy] = pixelSlopes(px, py, width, height);
    this.panMm = [this.panMm[0] + sx * travelled, this.panMm[1] + sy * travelled];
  }

  // The vpm.v3.Camera message.
  toProto() {
    return { azimuth_deg: this.azimuthDeg, elevation_deg: this.elevationDeg,
             distance_mm: this.distanceMm, pan_mm: { x: this.panMm[0], y: this.panMm[1], z: 0 } };
  }

  // Unit ray direction of pixel (px, py) of a width x height frame, row 0 at
  // the top (CameraRays::Direction).
  rayDirection(px, py, width, height) {
    const [sx, sy] = pixelSlopes(px, py, width, height);
    return normalize(add(this.forward(), add(scale(this.right(), sx), scale(this.up(), sy))));
  }

  // Frame position [px, py] (pixels, row 0 at the top, pixel centres at
  // +0.5) of physical point pMm; null when it is not in front of the eye.
  // The inverse of rayDirection (Camera::Project).
  projectToPixel(pMm, width, height) {
    const eye = this.eye();
    const v = add(pMm, scale(eye, -1));
    const depth = dot(v, this.forward());
    if (!(depth > 1e-6)) return null;
    const tanHalf = Math.tan(0.5 * kFovDeg * kDegToRad);
    const shorter = Math.max(1, Math.min(width, height));
    const nx = dot(v, this.right()) / (depth * tanHalf * width / shorter);
    const ny = dot(v, this.up()) / (depth * tanHalf * height / shorter);
    return [((nx + 1) * width) / 2, ((1 - ny) * height) / 2];
  }

  // The point a pick of pixel (px, py) grabs (Session::GrabPoint): the
  // pixel's ray meets the plane through the orbit centre facing the camera.
  pickPointMm(px, py, width, height) {
    const eye = this.eye(), f = this.forward();
    const dir = this.rayDirection(px, py, width, height);
    const t = dot(add(this.target(), scale(eye, -1)), f) / dot(dir, f);
    return add(eye, scale(dir, t));
  }

  insideVolume(pointMm) {
    return pointMm.every((v, a) => Number.isFinite(v) && v >= 0 && v <= this.extentMm[a]);
  }

  // Millimetres per pixel on the plane through the orbit centre (where
  // picks land) for a frame whose shorter side is shorterPx.
  mmPerPixel(width, height) {
    const shorter = Math.max(1, Math.min(width, height));
    return (2 * Math.tan(0.5 * kFovDeg * kDegToRad) * this.distanceMm) / shorter;
  }

  // The drag offset (mm, world LPS, as Drag.offset_mm) that follows the
  // pointer: a screen motion of (dxPx right, dyPx down) on a width x height
  // frame, applied on the orbit-centre plane so the grabbed tissue stays
  // under the pointer.
  dragOffsetMm(dxPx, dyPx, width, height) {
    const s = this.mmPerPixel(width, height);
    return this.worldDirection(add(scale(this.right(), dxPx * s), scale(this.up(), -dyPx * s)));
  }

  // The camera works in physical voxel space (index * spacing); the API in
  // world LPS: a direction turns (D v), a point also moves (origin + D p).
  worldDirection(v) {
    const c = this.columns;
    return [0, 1, 2].map((r) => c[0][r] * v[0] + c[1][r] * v[1] + c[2][r] * v[2]);
  }

  worldPoint(p) {
    return add(this.originLps, this.worldDirection(p));
  }
}
