// Signed-in browsers. A browser signs in once with a user's token (the
// form at /login, or `?token=` on any page, exchanged at once for a cookie
// and redirected away so the token leaves the address bar and history) and
// gets an HttpOnly, SameSite=Strict cookie (Secure under TLS). The cookie
// holds the sign-in sealed with AES-256-GCM under the gateway's cookie key:
// a random id, the user, the token the gateway forwards to vpm-server for
// that user, and the expiry. So the gateway keeps no state a restart or a
// second replica would lose (give every replica the same --cookie-key-file);
// without the key nothing in the cookie can be read or forged. Every use
// checks the token against the current users again. Sign-out revokes the id
// in this process (other replicas keep honouring the cookie until it
// expires) and closes that browser's tabs here. Failed sign-ins are limited
// per client address.
import crypto from 'node:crypto';

export const kCookieName = 'vpm_session';
export const kMaxSignInTokenBytes = 1024;  // the sealed cookie stays under 4 KiB
const kFailureWindowMs = 60 * 1000;
const kMaxFailureAddresses = 10000;
const kMaxRevoked = 100000;

export class SignIns {
  // users: a Users (users.js); key: 32 bytes (random when not given: sign-ins
  // end with the process); maxAgeS: cookie and sign-in lifetime; secure: the
  // page is served over TLS; maxFailuresPerMinute: per address.
  constructor({ users, key = crypto.randomBytes(32), maxAgeS = 12 * 3600, secure = false,
                maxFailuresPerMinute = 10 }) {
    if (key.length !== 32) throw new Error('the cookie key must be 32 bytes');
    Object.assign(this, { users, key, maxAgeS, secure, maxFailuresPerMinute });
    this.revoked = new Map();   // id -> expiresAt
    this.sockets = new Map();   // id -> Set of the tabs' WebSockets in this process
    this.failures = new Map();  // address -> {count, since}
  }

  // The sign-in of this request's cookie ({id, user, token, expiresAt}), or
  // null: no cookie, not sealed with this key, expired, revoked, or a token
  // no longer among the users.
  fromRequest(req) {
    const value = readCookie(req.headers.cookie, kCookieName);
    if (!value) return null;
    const signIn = this.open(value);
    if (!signIn || Date.now() > signIn.expiresAt || this.revoked.has(signIn.id)) return null;
    if (this.users.authenticate(signIn.token) !== signIn.user) return null;
    return signIn;
  }

  // Returns the new sign-in, or null for a wrong token. Throttled addresses
  // must be refused before (throttled()).
  signIn(token, address) {
    const user = Buffer.byteLength(String(token)) <= kMaxSignInTokenBytes
      ? this.users.authenticate(token) : null;
    if (!user) {
      this.failed(address);
      return null;
    }
    return { id: crypto.randomBytes(16).toString('base64url'), user, token,
             expiresAt: Date.now() + this.maxAgeS * 1000 };
  }

  // A tab of sign-in `id` in this process: closed on sign-out.
  addSocket(id, ws) {
    if (!this.sockets.has(id)) this.sockets.set(id, new Set());
    this.sockets.get(id).add(ws);
    ws.on('close', () => {
      const set = this.sockets.get(id);
      set?.delete(ws);
      if (set?.size === 0) this.sockets.delete(id);
    });
  }

  remove(signIn, why = 'signed out') {
    const now = Date.now();
    if (this.revoked.size >= kMaxRevoked) {
      for (const [id, expiresAt] of this.revoked) if (expiresAt < now) this.revoked.delete(id);
    }
    this.revoked.set(signIn.id, signIn.expiresAt);
    // The tab is told why, as the API ends a revoked stream, then closed.
    for (const ws of this.sockets.get(signIn.id) ?? []) {
      if (ws.readyState === ws.OPEN) {
        ws.send(JSON.stringify({ type: 'error', what: 'sign-in', code: 'PERMISSION_DENIED',
                                 message: why }));
      }
      ws.close(4001, why);
    }
  }

  cookie(signIn) {
    return `${kCookieName}=${this.seal(signIn)}; Path=/; HttpOnly; SameSite=Strict; ` +
           `Max-Age=${this.maxAgeS}${this.secure ? '; Secure' : ''}`;
  }

  clearedCookie() {
    return `${kCookieName}=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0${this.secure ? '; Secure' : ''}`;
  }

  // base64url(iv 12 | tag 16 | AES-256-GCM ciphertext of the JSON).
  seal({ id, user, token, expiresAt }) {
    const iv = crypto.randomBytes(12);
    const cipher = crypto.createCipheriv('aes-256-gcm', this.key, iv);
    const body = Buffer.concat([cipher.update(JSON.stringify({ i: id, u: user, t: token, e: expiresAt })),
                                cipher.final()]);
    return Buffer.concat([iv, cipher.getAuthTag(), body]).toString('base64url');
  }

  open(value) {
    try {
      const raw = Buffer.from(value, 'base64url');
      if (raw.length < 29) return null;
      const decipher = crypto.createDecipheriv('aes-256-gcm', this.key, raw.subarray(0, 12));
      decipher.setAuthTag(raw.subarray(12, 28));
      const json = Buffer.concat([decipher.update(raw.subarray(28)), decipher.final()]);
      const { i, u, t, e } = JSON.parse(json.toString('utf8'));
      if (typeof i !== 'string' || typeof u !== 'string' || typeof t !== 'string' ||
          !Number.isFinite(e)) return null;
      return { id: i, user: u, token: t, expiresAt: e };
    } catch {
      return null;  // not sealed with this key, or tampered with
    }
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
}

// The value of cookie `name` in a Cookie header, or null.
export function readCookie(header, name) {
  if (typeof header !== 'string' || header.length > 8192) return null;
  for (const part of header.split(';')) {
    const eq = part.indexOf('=');
    if (eq < 0) continue;
    if (part.slice(0, eq).trim() === name) {
      const value = part.slice(eq + 1).trim();
      return /^[A-Za-z0-9_-]{1,4000}$/.test(value) ? value : null;
    }
  }
  return null;
}
