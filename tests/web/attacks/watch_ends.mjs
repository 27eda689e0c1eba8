// Issue 25, point 2: access is checked for the life of a stream. Alice
// shares her session with bob (ShareSession over gRPC, as `vpm session
// share` does) and bob watches it through the gateway while alice orbits;
// then bob's access ends:
//  - revoke: alice revokes the share. The server must end bob's Watch with
//    PERMISSION_DENIED (the server's part, not in this tree yet: without it
//    bob's frames go on);
//  - close: alice's tab goes, so the gateway closes her session, and the
//    server ends its streams.
// Either way the gateway stops bob's frames at once and tells his page
// (access_ended, within 1 s), and neither watches again nor reopens.
import assert from 'node:assert/strict';

import { closeTab, frameClock, openView, orbit, sleep } from './view.mjs';

async function watchThenEnd(ctx, end) {
  const alice = await ctx.tab(await ctx.signIn('alice'));
  const bob = await ctx.tab(await ctx.signIn('bob'));
  try {
    const { session } = await openView(alice);
    const asAlice = { token: ctx.tokens.alice };
    await ctx.grpc.call('ShareSession', { session_id: session.session_id, user: 'bob' }, asAlice);
    bob.send({ type: 'watch', session_id: session.session_id, settings: { width: 64, height: 64 } });
    await bob.next((m) => m.type === 'opened' && m.watching === true, 10000);
    const times = frameClock(bob);
    const driving = orbit(alice, 1500);
    await sleep(700);
    assert.ok(times.length > 0, 'bob sees no frame of the shared session');
    const t0 = performance.now();
    await end({ alice, session, asAlice });
    const ended = await bob.next((m) => m.type === 'access_ended', 1000);
    const endedMs = performance.now() - t0;
    const at = performance.now();
    await driving.catch(() => {});
    await sleep(500);
    const late = times.filter((t) => t > at).length;
    assert.equal(late, 0, `bob got ${late} frames after the end was reported`);
    assert.ok(!bob.inbox.some((m) => m.type === 'session_lost' || m.type === 'opened'),
              'bob was told to reopen, or reopened');
    return { code: ended.code, ended_ms: Math.round(endedMs), frames_after: late };
  } finally {
    await closeTab(bob);
    if (alice.ws.readyState === alice.ws.OPEN) await closeTab(alice);
  }
}

export function runRevoke(ctx) {
  return watchThenEnd(ctx, async ({ session, asAlice }) => {
    await ctx.grpc.call('ShareSession', { session_id: session.session_id, user: 'bob', revoke: true },
                        asAlice);
  });
}

export function runClose(ctx) {
  return watchThenEnd(ctx, async ({ alice }) => {
    await closeTab(alice);
  });
}
