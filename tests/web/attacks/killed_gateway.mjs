// Issue 25, point 9: a killed gateway's sessions held the user's session
// cap for 15 minutes (the server's idle expiry). The server runs with
// --max-sessions-per-user 3: alice opens three tabs, the gateway is killed
// (SIGKILL: nothing closed), a new gateway starts on the same
// --sessions-file, and alice's next tab opens a view at once: the new
// gateway closed what the killed one left before opening hers, and alice
// holds one session on the server, not four.
import assert from 'node:assert/strict';

import { closeTab, openView, sleep } from './view.mjs';

const aliceSessions = (m) => m['vpm_user_sessions{user="alice"}'] ?? 0;

export async function run(ctx) {
  const cookie = await ctx.signIn('alice');
  const tabs = [];
  for (let i = 0; i < 3; ++i) {
    const tab = await ctx.tab(cookie);
    await openView(tab);
    tabs.push(tab);
  }
  assert.equal(aliceSessions(await ctx.metrics()), 3, 'alice does not hold three sessions');
  await ctx.killGateway();
  await Promise.all(tabs.map((t) => t.closed));
  await sleep(500);
  const afterKill = aliceSessions(await ctx.metrics());
  assert.equal(afterKill, 3, 'the server closed the sessions by itself');
  await ctx.startGateway();  // same cookie key: alice is still signed in
  const t0 = performance.now();
  const tab = await ctx.tab(cookie);
  try {
    await openView(tab, { timeoutMs: 30000 });
    const openMs = performance.now() - t0;
    const now = aliceSessions(await ctx.metrics());
    assert.equal(now, 1, `alice holds ${now} sessions on the server`);
    return { sessions_after_kill: afterKill, sessions_after_reopen: now, reopen_ms: Math.round(openMs) };
  } finally {
    await closeTab(tab);
  }
}
