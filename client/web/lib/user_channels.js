// One gRPC channel per signed-in user, so that one user's calls cannot
// stall another's: grpc-js multiplexes every call of a channel on one
// HTTP/2 connection, and a single call the server cannot finish (a status
// too large for its trailers, a stream whose window never opens) stalls
// that whole connection. Channels are keyed by a hash of the user's token
// (the token is the user as the server knows them) and counted by the
// tabs using them; a channel no tab holds is closed after kIdleCloseMs, so
// a reloading page finds its connection still up.
import crypto from 'node:crypto';

const kIdleCloseMs = 30000;

export class UserChannels {
  // makeStub: () => a new stub on a channel of its own.
  constructor(makeStub, { idleCloseMs = kIdleCloseMs } = {}) {
    Object.assign(this, { makeStub, idleCloseMs });
    this.byUser = new Map();  // key -> {stub, tabs, timer}
  }

  static key(token) {
    return crypto.createHash('sha256').update(String(token)).digest('base64url');
  }

  entry(token) {
    const key = UserChannels.key(token);
    let e = this.byUser.get(key);
    if (!e) {
      e = { stub: this.makeStub(), tabs: 0, timer: null };
      this.byUser.set(key, e);
      // A channel used without a tab (none today) still goes when idle.
      this.closeLater(key, e);
    }
    return { key, e };
  }

  stub(token) {
    return this.entry(token).e.stub;
  }

  // The user's connection looks stuck: a call on `stub` ran out its
  // deadline, or the server refused it a stream. Later calls go on a fresh
  // channel; what is under way on the old one goes on until it ends
  // (closing a grpc-js channel ends no call), so a user who stalled their
  // own connection recovers without waiting for it.
  renew(token, stub) {
    const e = this.byUser.get(UserChannels.key(token));
    if (!e || e.stub !== stub) return;
    e.stub = this.makeStub();
    stub.close();
  }

  acquire(token) {
    const { e } = this.entry(token);
    e.tabs += 1;
    clearTimeout(e.timer);
    e.timer = null;
  }

  release(token) {
    const key = UserChannels.key(token);
    const e = this.byUser.get(key);
    if (!e) return;
    e.tabs = Math.max(0, e.tabs - 1);
    if (e.tabs === 0) this.closeLater(key, e);
  }

  closeLater(key, e) {
    clearTimeout(e.timer);
    e.timer = setTimeout(() => {
      if (e.tabs > 0 || this.byUser.get(key) !== e) return;
      this.byUser.delete(key);
      e.stub.close();
    }, this.idleCloseMs);
    e.timer.unref?.();
  }

  // Channels open now (for tests and logs).
  get size() {
    return this.byUser.size;
  }

  closeAll() {
    for (const e of this.byUser.values()) {
      clearTimeout(e.timer);
      e.stub.close();
    }
    this.byUser.clear();
  }
}
