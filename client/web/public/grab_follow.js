// The slice planes follow the held grab's tissue (docs/WEB.md, "Slices"):
// through the point the server picked for the grab (Frame.grab_point_mm)
// plus the drag offset the page sent last, world LPS mm. A release puts
// them where the tissue comes to rest (the drag's end when the drag is
// kept, the grab point when it is not), and frames of an earlier grab, or
// of this one once released, no longer move them: they would leave the
// planes wherever the last of them was cast. A release before any frame
// named the grab's point places them when the first such frame arrives.
import { grabTargetMm } from './slice_planes.js';

export class GrabFollow {
  // throughPoint({x, y, z}): puts the planes through a world point
  // (SliceViews.throughPoint).
  constructor(throughPoint) {
    this.throughPoint = throughPoint;
    this.held = false;       // a grab sent and not yet released
    this.sequence = 0;       // the event sequence of the last grab sent
    this.offsetMm = null;    // the held grab's drag offset sent last, else null
    this.pointMm = null;     // the held grab's point ([x, y, z]) once a frame named it
    this.pending = null;     // {offsetMm}: released before a frame named the point
  }

  // A grab sent with event sequence `sequence`.
  grab(sequence) {
    Object.assign(this, { held: true, sequence, offsetMm: null, pointMm: null, pending: null });
  }

  drag(offsetMm) {
    this.offsetMm = offsetMm;
  }

  release(keep) {
    const offsetMm = keep ? this.offsetMm : null;
    if (this.pointMm) {
      this.throughPoint(grabTargetMm(this.pointMm, offsetMm));
    } else if (this.held) {
      this.pending = { offsetMm };
    }
    Object.assign(this, { held: false, offsetMm: null, pointMm: null });
  }

  // A frame's header (grab_point_mm, last_sequence) arrived.
  frame(h) {
    if (!h.grab_point_mm || h.last_sequence < this.sequence) return;
    if (this.held) {
      this.pointMm = h.grab_point_mm;
      this.throughPoint(grabTargetMm(h.grab_point_mm, this.offsetMm));
    } else if (this.pending) {
      this.throughPoint(grabTargetMm(h.grab_point_mm, this.pending.offsetMm));
      this.pending = null;
    }
  }
}
