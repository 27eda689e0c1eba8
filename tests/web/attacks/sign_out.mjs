// Issue 25, point 2 (the gateway's part): signing out ends that browser's
// streams and WebSockets at once. Alice's tab streams frames; she signs out
// (POST /logout with her cookie): the tab is told PERMISSION_DENIED and its
// WebSocket closes (4001) within
// 1 s, no frame arrives after, the server's open streams and alice's
// sessions fall back to what they were before the tab within 2 s, and the
// cookie opens nothing more.
import assert from 'node:assert/strict';

import { request } from '../gateway_client.mjs';
import { frameClock, openView, orbit, sleep } from './view.mjs';

async function waitMetrics(ctx, pred, timeoutMs) {
  const deadline = performance.now() + timeoutMs;
  for (;;) {
    const m = await ctx.metrics();
    if (pred(m) || performance.now() > deadline) return m;
    await sleep(50);
  }
}

const aliceSessions = (m) => m['vpm_user_sessions{user="alice"}'] ?? 0;
const aliceStreams = (m) => m['vpm_user_streams{user="alice"}'] ?? 0;

export async function run(ctx) {
  // Alice's streams of earlier cases may still be closing: counted from
  // when they are gone (the server's per-user gauges, not the total, which
  // other users' streams move).
  const start = await waitMetrics(ctx, (m) => aliceStreams(m) === 0, 5000);
  const cookie = await ctx.signIn('alice');
  const tab = await ctx.tab(cookie);
  await openView(tab);
  const times = frameClock(tab);
  const driving = orbit(tab, 1500);
  // The tab's stream registers on the server once its first frame is out;
  // on a loaded machine that can take longer than a frame's time.
  const streaming = await waitMetrics(ctx, (m) => aliceStreams(m) > aliceStreams(start), 5000);
  assert.ok(aliceStreams(streaming) > aliceStreams(start), 'no stream of alice open on the server');
  const t0 = performance.now();
  const out = await request(ctx.gateway.base, '/logout', { method: 'POST', headers: { Cookie: cookie } });
  assert.equal(out.status, 303);
  const closed = await Promise.race([tab.closed, sleep(1000).then(() => null)]);
  const closedMs = performance.now() - t0;
  assert.ok(closed, 'the tab was still open 1 s after signing out');
  assert.equal(closed.code, 4001);
  const told = tab.inbox.find((m) => m.type === 'error' && m.code === 'PERMISSION_DENIED');
  assert.ok(told, 'the tab was not told PERMISSION_DENIED before it closed');
  const after = await waitMetrics(ctx, (m) => aliceStreams(m) === aliceStreams(start) &&
                                  aliceSessions(m) === aliceSessions(start), 2000);
  const settledMs = performance.now() - t0;
  await driving;
  assert.equal(aliceStreams(after), aliceStreams(start), 'the stream outlived the sign-out');
  assert.equal(aliceSessions(after), aliceSessions(start), 'the session outlived the sign-out');
  assert.equal(times.filter((t) => t > t0 + closedMs).length, 0, 'frames after the sign-out');
  await assert.rejects(ctx.tab(cookie), /401/);
  return { closed_ms: Math.round(closedMs), server_settled_ms: Math.round(settledMs) };
}
