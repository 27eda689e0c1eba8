// How far a patch of one grey image moved in another: the offset that best
// matches the patch, with the second image optionally scaled about the
// patch's centre (a zoom about that point). Grey levels 0..255, row-major.

// Bilinear grey level at (x, y) (pixel centres at integer + 0.5), or NaN off the image.
function sample(grey, w, h, x, y) {
  const fx = x - 0.5, fy = y - 0.5;
  const x0 = Math.floor(fx), y0 = Math.floor(fy);
  if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h) return NaN;
  const ax = fx - x0, ay = fy - y0;
  const at = (i, j) => grey[j * w + i];
  return (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
         ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
}

// before, after: grey arrays of w x h; centre: [x, y] frame px; scale: how
// much larger `after` shows things about `centre`; radius: the patch's
// half side; search: the largest offset tried (px, whole pixels). Returns
// {shift: [dx, dy], error}: where the patch's centre went, relative to
// centre, and the mean |grey difference| of that best match.
export function bestShift(before, after, w, h, centre, scale, radius, search) {
  let best = { shift: [0, 0], error: Infinity };
  for (let oy = -search; oy <= search; ++oy) {
    for (let ox = -search; ox <= search; ++ox) {
      let sum = 0, n = 0;
      for (let qy = -radius; qy <= radius; qy += 2) {
        for (let qx = -radius; qx <= radius; qx += 2) {
          const bx = centre[0] + qx, by = centre[1] + qy;
          const a = sample(after, w, h, centre[0] + scale * qx + ox, centre[1] + scale * qy + oy);
          const b = sample(before, w, h, bx, by);
          if (Number.isNaN(a) || Number.isNaN(b)) continue;
          sum += Math.abs(a - b);
          n += 1;
        }
      }
      if (n > 0.5 * (radius + 1) * (radius + 1) && sum / n < best.error) {
        best = { shift: [ox, oy], error: sum / n };
      }
    }
  }
  return best;
}
