// The gateway's channel per user (client/web/lib/user_channels.js): one
// stub per token, shared by that user's tabs, another user's never the
// same; closed once idle after the user's last tab, kept while a tab holds
// it; renewed once when a call on it got stuck. (That each channel has a connection of its own is gateway.test.mjs's
// Gateway_EachUserHasAConnectionOfTheirOwn.)
// Usage: node --test user_channels.test.mjs
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { UserChannels } from '../../client/web/lib/user_channels.js';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

function fakeStubs() {
  const made = [];
  const make = () => {
    const stub = { closed: false, close() { this.closed = true; } };
    made.push(stub);
    return stub;
  };
  return { made, make };
}

test('UserChannels_OneChannelPerUserSharedByTheirTabs', () => {
  const { made, make } = fakeStubs();
  const channels = new UserChannels(make, { idleCloseMs: 50 });
  channels.acquire('alice-token');
  channels.acquire('alice-token');
  channels.acquire('bob-token');
  assert.equal(channels.stub('alice-token'), channels.stub('alice-token'));
  assert.notEqual(channels.stub('alice-token'), channels.stub('bob-token'));
  assert.equal(made.length, 2);
  assert.equal(channels.size, 2);
  channels.closeAll();
  assert.ok(made.every((s) => s.closed));
});

test('UserChannels_ClosedOnceIdleAfterTheLastTab', async () => {
  const { made, make } = fakeStubs();
  const channels = new UserChannels(make, { idleCloseMs: 50 });
  channels.acquire('alice-token');
  channels.acquire('alice-token');
  channels.release('alice-token');
  await sleep(120);
  assert.equal(made[0].closed, false, 'closed while a tab holds it');
  channels.release('alice-token');
  channels.acquire('alice-token');  // a reload: the same channel again
  await sleep(120);
  assert.equal(made.length, 1);
  assert.equal(made[0].closed, false);
  channels.release('alice-token');
  await sleep(120);
  assert.equal(made[0].closed, true);
  assert.equal(channels.size, 0);
  channels.acquire('alice-token');
  assert.equal(made.length, 2, 'no new channel after the idle one closed');
  channels.closeAll();
});

test('UserChannels_RenewGivesTheUserAFreshChannelOnce', () => {
  const { made, make } = fakeStubs();
  const channels = new UserChannels(make, { idleCloseMs: 50 });
  channels.acquire('alice-token');
  channels.acquire('bob-token');
  const [stuck, bobs] = [channels.stub('alice-token'), channels.stub('bob-token')];
  channels.renew('alice-token', stuck);
  channels.renew('alice-token', stuck);  // a second call failing on the old one
  assert.equal(stuck.closed, true);
  assert.notEqual(channels.stub('alice-token'), stuck);
  assert.equal(made.length, 3, 'renewed more than once');
  assert.equal(channels.stub('bob-token'), bobs, "bob's channel renewed");
  assert.equal(bobs.closed, false);
  channels.closeAll();
});
