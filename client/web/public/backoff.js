// Exponential backoff with jitter, for reconnecting (the browser to the
// gateway, the gateway to vpm-server). Shared by both: an ES module with no
// dependencies.
export class Backoff {
  // Delays in ms: first, then x factor each failure up to max; +-jitter share.
  constructor({ firstMs = 250, maxMs = 5000, factor = 2, jitter = 0.2 } = {}) {
    Object.assign(this, { firstMs, maxMs, factor, jitter });
    this.failures = 0;
  }

  // The delay before the next attempt, ms; counts one more failure.
  next() {
    const base = Math.min(this.maxMs, this.firstMs * this.factor ** this.failures);
    this.failures += 1;
    return Math.round(base * (1 + this.jitter * (2 * Math.random() - 1)));
  }

  reset() {
    this.failures = 0;
  }
}
