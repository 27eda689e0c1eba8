// Issue 25, point 1: one signed-in user freezes the web viewer for everyone.
// Alice sends the transfer-function message whose text the server quotes
// back in its error (50,000 '%', percent-encoded to 150 kB, past what the
// server can put in its trailers: the HTTP/2 connection of that call
// stalls). The gateway gives each user a connection of their own, so bob's
// view goes on: his frame rate in the 4 s after the attack is at least half
// of his rate in the 4 s before, with no gap over 1 s, and alice gets a
// bounded error (or nothing) on her own page.
import assert from 'node:assert/strict';

import { closeTab, frameClock, framesIn, openView, orbit, sleep } from './view.mjs';

const kWindowMs = 4000;
// The message, its "..." the rest of a Slicer .vp (9 lines in all),
// so that the server reads as far as line 7 and quotes its bad number.
export const kCase1Text = `1\n0\n0\n0\n0\n1\n2 ${'%'.repeat(50000)} 1\n2 0 1 255 1\n` +
  '8 0 0 0 0 255 1 1 1\n';

export async function run(ctx) {
  const bob = await ctx.tab(await ctx.signIn('bob'));
  const alice = await ctx.tab(await ctx.signIn('alice'));
  try {
    await openView(bob);
    await alice.next((m) => m.type === 'volumes', 10000);
    const times = frameClock(bob);
    const driving = orbit(bob, 2 * kWindowMs + 500);
    await sleep(250);
    const t0 = performance.now();
    await sleep(kWindowMs);
    const t1 = performance.now();
    alice.send({ type: 'tf', file_name: 'x.vp', text: kCase1Text });
    await sleep(kWindowMs);
    const t2 = performance.now();
    const last = await driving;
    const before = framesIn(times, t0, t1);
    const during = framesIn(times, t1, t2);
    ctx.step(`bob before the attack: ${before.frames} frames (${before.fps.toFixed(1)} fps), ` +
             `after: ${during.frames} (${during.fps.toFixed(1)} fps, longest gap ` +
             `${during.longestGapMs.toFixed(0)} ms)`);
    assert.ok(before.frames >= 10, `bob got only ${before.frames} frames without the attack`);
    assert.ok(during.frames >= before.frames / 2,
              `bob's frames fell from ${before.frames} to ${during.frames} in ${kWindowMs} ms`);
    assert.ok(during.longestGapMs <= 1000, `bob got no frame for ${during.longestGapMs} ms`);
    // Alice's own page: whatever she is told is bounded.
    const told = await alice.next((m) => m.type === 'error', 15000).catch(() => null);
    if (told) {
      assert.ok(told.message.length <= 1000, `alice's error is ${told.message.length} characters`);
    }
    // Bob still drives his view after alice's call is over.
    const again = times.length;
    await orbit(bob, 1000, { from: last });
    await sleep(300);
    assert.ok(times.length > again, 'bob got no frame after the attack');
    return { bob_fps_before: Number(before.fps.toFixed(1)), bob_fps_during: Number(during.fps.toFixed(1)),
             bob_longest_gap_ms: Math.round(during.longestGapMs),
             alice_told: told ? `${told.code}: ${told.message.slice(0, 120)}` : null };
  } finally {
    await closeTab(alice);
    await closeTab(bob);
  }
}
