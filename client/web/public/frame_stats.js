// The status line's figures: frames per second over the last second, the
// round-trip latency from sending event n to the first frame that reports
// last_sequence n (ms; coalesced events count from the newest one shown).
const kWindowMs = 1000;

export class FrameStats {
  constructor() {
    this.sentAt = new Map();  // sequence -> performance.now() when sent
    this.arrivals = [];       // performance.now() of recent frames
    this.latencyMs = null;
    this.frames = 0;
  }

  sent(sequence) {
    this.sentAt.set(sequence, performance.now());
  }

  // header: the frame header from the gateway.
  frame(header) {
    const now = performance.now();
    this.frames += 1;
    this.arrivals.push(now);
    while (this.arrivals.length && this.arrivals[0] < now - kWindowMs) this.arrivals.shift();
    const shown = this.sentAt.get(header.last_sequence);
    for (const sequence of this.sentAt.keys()) {
      if (sequence <= header.last_sequence) this.sentAt.delete(sequence);
    }
    if (shown !== undefined) this.latencyMs = now - shown;
  }

  fps() {
    const now = performance.now();
    return this.arrivals.filter((t) => t >= now - kWindowMs).length;
  }
}
