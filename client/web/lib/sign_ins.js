// Signed-in browsers. A browser signs in once with a user's token (the
// form at /login, or `?token=` on any page, exchanged at once for a cookie
// and redirected away so the token leaves the address bar and history) and
// gets a random session id in an HttpOnly, SameSite=Strict cookie (Secure
// under TLS). The gateway keeps, per id, the user and the token it forwards
// to vpm-server; ids expire after maxAgeS and on sign-out, which also closes
// that browser's tabs. Failed sign-ins are limited per client address.
import crypto from 'node:crypto';

export const kCookieName = 'vpm_session';
const kMaxSignIns = 10000;
const kFailureWindowMs = 60 * 1000;
const kMaxFailureAddresses = 10000;

export class SignIns {
  // users: a Users (users.js); maxAgeS: cookie and sign-in lifetime;
  // secure: the page is served over TLS; maxFailuresPerMinute: per address.
  constructor({ users, maxAgeS = 12 * 3600, secure = false, maxFailuresPerMinute = 10 }) {
    Object.assign(this, { users, maxAgeS, secure, maxFailuresPerMinute });
    this.byId = new Map();      // id -> {id, user, token, expiresAt, sockets: Set}
    this.failures = new Map();  // address -> {count, since}
  }

  // The sign-in of this request's cookie, or null.
  fromRequest(req) {
    const id = readCookie(req.headers.cookie, kCookieName);
    if (!id) return null;
    const signIn = this.byId.get(id);
    if (!signIn) return null;
    if (Date.now() > signIn.expiresAt) {
      this.remove(id, 'the sign-in expired');
      return null;
    }
    return signIn;
  }

  // Returns the new sign-in, or null for a wrong token. Throttled addresses
  // must be refused before (throttled()).
  signIn(token, address) {
    const user = this.users.authenticate(token);
    if (!user) {
      this.failed(address);
      return null;
    }
    this.prune();
    const id = crypto.randomBytes(32).toString('base64url');
    const signIn = { id, user, token, expiresAt: Date.now() + this.maxAgeS * 1000,
                     sockets: new Set() };
    this.byId.set(id, signIn);
    return signIn;
  }

  remove(id, why = 'signed out') {
    const signIn = this.byId.get(id);
    if (!signIn) return;
    this.byId.delete(id);
    for (const ws of signIn.sockets) ws.close(4001, why);
  }

  cookie(signIn) {
    return `${kCookieName}=${signIn.id}; Path=/; HttpOnly; SameSite=Strict; ` +
           `Max-Age=${this.maxAgeS}${this.secure ? '; Secure' : ''}`;
  }

  clearedCookie() {
    return `${kCookieName}=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0${this.secure ? '; Secure' : ''}`;
  }

  // Seconds until `address` may try again, or 0.
  throttled(address) {
    const f = this.failures.get(address);
    if (!f) return 0;
    const left = f.since + kFailureWindowMs - Date.now();
    if (left <= 0) {
      this.failures.delete(address);
      return 0;
    }
    return f.count >= this.maxFailuresPerMinute ? Math.ceil(left / 1000) : 0;
  }

  failed(address) {
    const now = Date.now();
    const f = this.failures.get(address);
    if (!f || now - f.since > kFailureWindowMs) {
      if (this.failures.size >= kMaxFailureAddresses) this.failures.clear();
      this.failures.set(address, { count: 1, since: now });
    } else {
      f.count += 1;
    }
  }

  // Drops expired sign-ins; past kMaxSignIns, the oldest.
  prune() {
    const now = Date.now();
    for (const [id, s] of this.byId) {
      if (now > s.expiresAt) this.remove(id, 'the sign-in expired');
    }
    while (this.byId.size >= kMaxSignIns) this.remove(this.byId.keys().next().value, 'too many sign-ins');
  }
}

// The value of cookie `name` in a Cookie header, or null.
export function readCookie(header, name) {
  if (typeof header !== 'string' || header.length > 8192) return null;
  for (const part of header.split(';')) {
    const eq = part.indexOf('=');
    if (eq < 0) continue;
    if (part.slice(0, eq).trim() === name) {
      const value = part.slice(eq + 1).trim();
      return /^[A-Za-z0-9_-]{1,128}$/.test(value) ? value : null;
    }
  }
  return null;
}
