// The sessions this gateway opened on vpm-server and has not closed, kept in
// a file (--sessions-file) so that a gateway killed without closing them
// (SIGKILL, a crash, a lost node) does not leave them holding their users'
// session cap until the server's idle expiry (--idle-session-s, 15 min).
// The file holds session ids and user names only, never a token: the
// gateway started again reads what the last process left, and closes a
// user's leftovers as that user (CloseSession with their token) when a tab
// of theirs connects, before it opens anything. One file per gateway
// process: replicas must not share one.
//
// File: JSON {"sessions": [{"user": NAME, "id": SESSION_ID}, ...]}, written
// to FILE.tmp and renamed over FILE on every change.
import fs from 'node:fs';

const kMaxRecorded = 100000;  // far above any --max-sessions

export class SessionRecord {
  // file: the path, or null (nothing kept: a record in memory only).
  // log: (line) => void.
  constructor(file = null, log = () => {}) {
    Object.assign(this, { file, log });
    this.open = new Map();       // id -> user: opened by this process
    this.leftovers = new Map();  // user -> Set of ids left by an earlier process
    this.closing = new Map();    // user -> the promise of closeLeftovers under way
    if (file) this.load();
  }

  load() {
    let text;
    try {
      text = fs.readFileSync(this.file, 'utf8');
    } catch (e) {
      if (e.code !== 'ENOENT') this.log(`--sessions-file ${this.file}: ${e.message}`);
      return;
    }
    try {
      for (const { user, id } of JSON.parse(text).sessions ?? []) {
        if (typeof user !== 'string' || typeof id !== 'string') continue;
        if (!this.leftovers.has(user)) this.leftovers.set(user, new Set());
        this.leftovers.get(user).add(id);
      }
    } catch (e) {
      this.log(`--sessions-file ${this.file}: not a record (${e.message}); starting afresh`);
    }
    const n = [...this.leftovers.values()].reduce((sum, s) => sum + s.size, 0);
    if (n) this.log(`${n} session(s) left open by an earlier gateway: closed as their users return`);
  }

  opened(user, id) {
    if (this.open.size >= kMaxRecorded) return;
    this.open.set(id, user);
    this.save();
  }

  closed(id) {
    let changed = this.open.delete(id);
    for (const [user, ids] of this.leftovers) {
      changed = ids.delete(id) || changed;
      if (ids.size === 0) this.leftovers.delete(user);
    }
    if (changed) this.save();
  }

  // Closes what an earlier process left open for `user`: close(id) resolves
  // true once the session is closed or gone (or is not the user's), false
  // when it should be tried again on the user's next tab (server down).
  // One run per user at a time; resolves when it is over, never rejects.
  closeLeftovers(user, close) {
    if (!this.leftovers.has(user)) return Promise.resolve();
    if (this.closing.has(user)) return this.closing.get(user);
    const ids = [...this.leftovers.get(user)];
    let closedNow = 0;
    const run = Promise.all(ids.map((id) => Promise.resolve()
      .then(() => close(id))
      .then((done) => {
        if (!done) return;
        closedNow += 1;
        this.closed(id);
      }, () => {})))
      .then(() => {
        this.closing.delete(user);
        this.log(`closed ${closedNow} of ${ids.length} session(s) of ${user} left by an ` +
                 'earlier gateway');
      });
    this.closing.set(user, run);
    return run;
  }

  // A session this process could not close (the server was down): closed
  // on the user's next tab, by this process or the next.
  leftOver(id) {
    const user = this.open.get(id);
    if (user === undefined) return;
    this.open.delete(id);
    if (!this.leftovers.has(user)) this.leftovers.set(user, new Set());
    this.leftovers.get(user).add(id);
    this.save();
  }

  get size() {
    return this.open.size + [...this.leftovers.values()].reduce((sum, s) => sum + s.size, 0);
  }

  save() {
    if (!this.file) return;
    const sessions = [...this.open].map(([id, user]) => ({ user, id }));
    for (const [user, ids] of this.leftovers) for (const id of ids) sessions.push({ user, id });
    try {
      fs.writeFileSync(`${this.file}.tmp`, JSON.stringify({ sessions }), { mode: 0o600 });
      fs.renameSync(`${this.file}.tmp`, this.file);
    } catch (e) {
      this.log(`--sessions-file ${this.file}: cannot write (${e.message})`);
    }
  }
}
