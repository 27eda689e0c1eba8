// The people who may sign in to the gateway. The same users file as
// vpm-server's --users (one `NAME TOKEN-SHA256 [browse-data-root]` a line, '#' comments; see
// server/service/users_file.h), and/or one viewer token (--viewer-token-file,
// VPM_VIEWER_TOKEN, else VPM_TOKEN: the server's own token, user `viewer`).
// A user signs in with their token; the gateway keeps it (in memory, with
// the sign-in) and forwards it to vpm-server as that user's bearer token,
// so the server knows who is calling. Only hashes are kept for checking.
import crypto from 'node:crypto';
import fs from 'node:fs';

export const kViewerUser = 'viewer';
export const kBrowseDataRoot = 'browse-data-root';
const kNamePattern = /^[A-Za-z0-9._-]{1,64}$/;
const kMaxTokenBytes = 4096;

export function hashToken(token) {
  return crypto.createHash('sha256').update(token, 'utf8').digest('hex');
}

// text: the file's contents; file: its name for messages. Throws an Error
// naming the line for a malformed line, a bad name or hash, or a name or
// hash given twice.
export function parseUsersFile(text, file) {
  const users = [];
  const names = new Set();
  const hashes = new Set();
  text.split('\n').forEach((raw, i) => {
    const fields = raw.replace(/\r$/, '').trim().split(/[ \t]+/).filter(Boolean);
    if (fields.length === 0 || fields[0].startsWith('#')) return;
    const bad = (why) => new Error(`--users ${file} line ${i + 1}: ${why} ` +
                                   "(each line is 'NAME TOKEN-SHA256 [browse-data-root]')");
    if (fields.length < 2) throw bad(`${fields.length} fields, not 2`);
    const [name, hash, ...permissions] = fields;
    // vpm-server's permissions (users_file.h); the server enforces them.
    const unknown = permissions.find((p) => p !== kBrowseDataRoot);
    if (unknown !== undefined) throw bad(`unknown permission '${unknown.slice(0, 64)}'`);
    if (!kNamePattern.test(name)) throw bad(`user name '${name}': 1 to 64 of [A-Za-z0-9._-]`);
    if (!/^[0-9a-fA-F]{64}$/.test(hash)) throw bad('the hash must be 64 hexadecimal digits');
    if (names.has(name)) throw bad(`user '${name}' given twice`);
    if (hashes.has(hash.toLowerCase())) throw bad(`user '${name}' has the token of an earlier user`);
    names.add(name);
    hashes.add(hash.toLowerCase());
    users.push({ name, hash: hash.toLowerCase() });
  });
  if (users.length === 0) throw new Error(`--users ${file}: no users`);
  return users;
}

export class Users {
  // users: [{name, hash}]; viewerToken: a token for the user `viewer`, or ''.
  constructor({ users = [], viewerToken = '' }) {
    this.users = [...users];
    if (viewerToken) {
      if (this.users.some((u) => u.name === kViewerUser)) {
        throw new Error(`--users names a user '${kViewerUser}', which is the viewer token's`);
      }
      this.users.push({ name: kViewerUser, hash: hashToken(viewerToken) });
    }
    if (this.users.length === 0) {
      throw new Error('no users: give --users FILE, --viewer-token-file FILE, or set ' +
                      'VPM_VIEWER_TOKEN (or VPM_TOKEN)');
    }
  }

  static fromFile(file, viewerToken) {
    return new Users({ users: file ? parseUsersFile(fs.readFileSync(file, 'utf8'), file) : [],
                       viewerToken });
  }

  // The user whose token this is, or null. Every user's hash is compared
  // (timingSafeEqual, no early exit), so timing says nothing of which.
  authenticate(token) {
    if (typeof token !== 'string' || token === '' || Buffer.byteLength(token) > kMaxTokenBytes) {
      return null;
    }
    const hash = Buffer.from(hashToken(token), 'hex');
    let match = null;
    for (const user of this.users) {
      if (crypto.timingSafeEqual(hash, Buffer.from(user.hash, 'hex'))) match = user.name;
    }
    return match;
  }
}
