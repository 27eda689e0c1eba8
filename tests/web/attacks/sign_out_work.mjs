// Issue 25, points 2 and 4 (the gateway's part): signing out ends the work a
// tab started on the server, not only its streams. Alice's tab opens a large
// volume of the data root (big.nii.gz, a 256^3 phantom: its load reads for a
// second or more); while the server reads it she signs out. The gateway
// cancels the tab's calls, and the server's reader stops at its next poll
// of the call's CancelToken: no call of alice's is in flight within 0.5 s
// and she holds no session (before, the load ran to its end and the tab's
// open went on).
import assert from 'node:assert/strict';

import { request } from '../gateway_client.mjs';
import { sleep } from './view.mjs';

const inFlight = (m, method) => m[`vpm_unary_calls_in_flight{method="${method}"}`] ?? 0;
const allInFlight = (m) => Object.entries(m)
  .filter(([k]) => k.startsWith('vpm_unary_calls_in_flight{'))
  .reduce((sum, [, v]) => sum + v, 0);
const aliceSessions = (m) => m['vpm_user_sessions{user="alice"}'] ?? 0;

// Polls the server's metrics until `pred` holds; a scrape the busy server
// drops (its HTTP endpoint hangs up now and then) is tried again.
async function waitMetrics(ctx, pred, timeoutMs, everyMs = 10) {
  const deadline = performance.now() + timeoutMs;
  for (;;) {
    const m = await ctx.metrics().catch(() => null);
    if ((m && pred(m)) || performance.now() > deadline) return m ?? ctx.metrics();
    await sleep(everyMs);
  }
}

export async function run(ctx) {
  const start = await waitMetrics(ctx, (m) => allInFlight(m) === 0, 10000);
  const cookie = await ctx.signIn('alice');
  const tab = await ctx.tab(cookie);
  let signedOut = false;
  const signOut = () => {
    signedOut = true;
    return request(ctx.gateway.base, '/logout', { method: 'POST', headers: { Cookie: cookie } });
  };
  try {
    tab.send({ type: 'open', source: 'big.nii.gz', settings: { width: 64, height: 64 } });
    const loading = await waitMetrics(ctx, (m) => inFlight(m, 'LoadVolume') > 0, 10000, 2);
    assert.ok(inFlight(loading, 'LoadVolume') > 0, 'no LoadVolume ran on the server');
    await sleep(100);  // well into the read
    const stillLoading = await waitMetrics(ctx, () => true, 1000);
    assert.ok(inFlight(stillLoading, 'LoadVolume') > 0, 'the load ended before the sign-out');
    const t0 = performance.now();
    const out = await signOut();
    assert.equal(out.status, 303);
    const after = await waitMetrics(ctx, (m) => allInFlight(m) === 0, 30000);
    const stoppedMs = performance.now() - t0;
    const settled = await waitMetrics(ctx, (m) => aliceSessions(m) === aliceSessions(start), 2000);
    assert.equal(allInFlight(after), 0, 'calls still in flight 30 s after the sign-out');
    assert.ok(stoppedMs < 500,
              `the server's work went on ${Math.round(stoppedMs)} ms after the sign-out`);
    assert.equal(aliceSessions(settled), aliceSessions(start), 'a session outlived the sign-out');
    return { work_stopped_ms: Math.round(stoppedMs) };
  } finally {
    // Nothing of this case may hold alice's caps for the next ones.
    if (!signedOut) await signOut().catch(() => {});
    await waitMetrics(ctx, (m) => aliceSessions(m) === aliceSessions(start), 5000);
  }
}
