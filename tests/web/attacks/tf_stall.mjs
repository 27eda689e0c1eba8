// Issue 25, point 1: one signed-in user froze the web viewer for everyone.
// Alice sends transfer-function messages whose text the server would quote
// back in its error (50,000 '%', percent-encoded to 150 kB, past what the
// server can put in its trailers: the HTTP/2 connection of that call
// stalls) while bob orbits his view. Two attacks:
//  - the case-1 message (a Slicer .vp): the gateway refuses it at
//    once (no .vp field is that long), with a short error on alice's page;
//  - the same 50,000 '%' as a ParaView preset's name (a .json the gateway
//    passes on): it reaches the server and stalls alice's connection, but
//    bob's calls go on a connection of his own.
// Each time, bob's frames in the 4 s after the message are at least half of
// those in the 4 s before, with no gap over 1 s, and alice's page gets a
// bounded error; once told, alice's next call answers within 5 s (the
// gateway gave her a fresh connection).
import assert from 'node:assert/strict';

import { closeTab, frameClock, framesIn, openView, orbit, sleep } from './view.mjs';

const kWindowMs = 4000;
const kPercents = '%'.repeat(50000);
// The message, its "..." the rest of a Slicer .vp (9 lines in all),
// so that a server reads as far as line 7 and quotes its bad number.
export const kCase1 = { type: 'tf', file_name: 'x.vp',
                        text: `1\n0\n0\n0\n0\n1\n2 ${kPercents} 1\n2 0 1 255 1\n8 0 0 0 0 255 1 1 1\n` };
// A preset without RGBPoints: the server's error names the preset.
export const kLongName = { type: 'tf', file_name: 'x.json', text: JSON.stringify([{ Name: kPercents }]) };

// Bob's frames over kWindowMs before and after alice sends `attack`.
async function bobAround(ctx, bob, alice, attack, times, from) {
  const driving = orbit(bob, 2 * kWindowMs + 500, { from });
  await sleep(250);
  const t0 = performance.now();
  await sleep(kWindowMs);
  const t1 = performance.now();
  alice.send(attack);
  await sleep(kWindowMs);
  const t2 = performance.now();
  const last = await driving;
  const before = framesIn(times, t0, t1);
  const during = framesIn(times, t1, t2);
  ctx.step(`${attack.file_name}: bob before: ${before.frames} frames (${before.fps.toFixed(1)} fps), ` +
           `after: ${during.frames} (${during.fps.toFixed(1)} fps, longest gap ` +
           `${during.longestGapMs.toFixed(0)} ms)`);
  assert.ok(before.frames >= 10, `bob got only ${before.frames} frames without the attack`);
  assert.ok(during.frames >= before.frames / 2,
            `${attack.file_name}: bob's frames fell from ${before.frames} to ${during.frames}`);
  assert.ok(during.longestGapMs <= 1000,
            `${attack.file_name}: bob got no frame for ${during.longestGapMs} ms`);
  return { last, before: Number(before.fps.toFixed(1)), during: Number(during.fps.toFixed(1)),
           gap_ms: Math.round(during.longestGapMs) };
}

export async function run(ctx) {
  const bob = await ctx.tab(await ctx.signIn('bob'));
  const alice = await ctx.tab(await ctx.signIn('alice'));
  try {
    await openView(bob);
    await alice.next((m) => m.type === 'volumes', 10000);
    const times = frameClock(bob);
    const vp = await bobAround(ctx, bob, alice, kCase1, times, 0);
    const refused = await alice.next((m) => m.type === 'error', 1000);
    assert.match(refused.message, /line 7 of the \.vp has a field of 50000 characters/);
    assert.ok(refused.message.length <= 300, `alice's error is ${refused.message.length} characters`);
    const json = await bobAround(ctx, bob, alice, kLongName, times, vp.last);
    // Alice's call waits out its deadline on her own stalled connection (or
    // the server answers): either way her page is told in bounded words.
    const told = await alice.next((m) => m.type === 'error', 15000);
    assert.ok(told.message.length <= 1000, `alice's error is ${told.message.length} characters`);
    // And she is not left on a stalled connection: her next call answers.
    const t3 = performance.now();
    alice.send({ type: 'list' });
    await alice.next((m) => m.type === 'volumes', 5000);
    const aliceBackMs = performance.now() - t3;
    // Bob still drives his view after alice's call is over.
    const again = times.length;
    await orbit(bob, 1000, { from: json.last });
    await sleep(300);
    assert.ok(times.length > again, 'bob got no frame after the attack');
    return { vp_bob_fps: [vp.before, vp.during], vp_bob_gap_ms: vp.gap_ms,
             json_bob_fps: [json.before, json.during], json_bob_gap_ms: json.gap_ms,
             alice_vp: refused.message.slice(0, 120), alice_json: `${told.code}: ${told.message.slice(0, 120)}`,
             alice_back_ms: Math.round(aliceBackMs) };
  } finally {
    await closeTab(alice);
    await closeTab(bob);
  }
}
