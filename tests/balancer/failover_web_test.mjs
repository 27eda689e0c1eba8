// The web viewer behind HAProxy (docker/haproxy.cfg): three vpm-server
// replicas on loopback sharing one data root, one gateway whose single gRPC
// channel to the balancer carries every tab's calls (one x-vpm-session key
// per tab), and two tabs in headless Chromium on different replicas, each
// opened from the "Loaded on the server" list (a volume id of its replica).
// The replica of tab A is killed (SIGKILL) while tab B orbits:
//  - tab B's frames never stall (no gap over 2.5 s in the 4 s after the
//    kill) and its session stays;
//  - tab A says why (the replica behind the balancer went away), reopens by
//    itself on a survivor (the volume loaded again from its source in the
//    data root, since the old id named the dead replica's volume) and shows
//    a frame that is not blank.
// Usage: node failover_web_test.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';

import {
  canvasGrey, launchBrowser, runScenario, settled, signInWithForm, startGateway,
} from '../web/harness.mjs';
import {
  exited, framesSince, kToken, makeDataRoot, replicaOf, sleep, startBalancer, startReplicas,
  testPaths,
} from './cluster.mjs';

const { build, source, out } = testPaths(process.argv, 'failover_web');
const step = (text) => console.log(`balancer_failover_web: ${text}`);
const kMaxGapMs = 2500;

// A tab (a browser context of its own, signed in with the gateway's token)
// with the data root's volume open from the loaded list; every text the
// page shows in #message is kept in window.messages.
async function openTab(browser, url) {
  // bypassCSP: the string predicates of settled() are evaluated in the
  // page, which the gateway's Content-Security-Policy would refuse.
  const page = await browser.newPage({ viewport: { width: 900, height: 800 }, bypassCSP: true });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await signInWithForm(page, url, kToken);
  await page.evaluate(() => {
    window.messages = [];
    const m = document.getElementById('message');
    new MutationObserver(() => window.messages.push(m.textContent))
      .observe(m, { childList: true, characterData: true, subtree: true });
  });
  await page.waitForSelector('#server-state[data-state="up"]', { timeout: 20000 });
  await page.waitForSelector('#loaded option', { state: 'attached', timeout: 20000 });
  const value = await page.getAttribute('#loaded option', 'value');
  await page.selectOption('#volume', value);
  await page.selectOption('#frame-size', '256');
  await page.click('#open');
  await settled(page, '!h.interactive', 60000);
  const session = await page.evaluate(() => window.vpmViewer.session.session_id);
  return { page, errors, session, opened: value };
}

async function main() {
  const { dataRoot, source: volumeSource } = await makeDataRoot(build, out);
  const replicas = await startReplicas({ build, out, n: 3, dataRoot, source: volumeSource });
  const balancer = await startBalancer({ source, out, replicas });
  const gateway = await startGateway({ source, out, serverAddress: balancer.address,
                                       token: kToken });
  const browser = await launchBrowser(source);

  // Tabs (each with its own random key) until two are on different replicas.
  const a = await openTab(browser, gateway.url);
  let b = null;
  for (let attempt = 0; attempt < 16 && !b; ++attempt) {
    const tab = await openTab(browser, gateway.url);
    if (replicaOf(replicas, tab.session) !== replicaOf(replicas, a.session)) b = tab;
    else await tab.page.close();
  }
  assert.ok(b, 'the keys of 17 tabs all hashed to one replica');
  const victim = replicaOf(replicas, a.session);
  const other = replicaOf(replicas, b.session);
  step(`tab A (${a.opened}) on ${victim.name}, tab B on ${other.name}, through one gateway`);

  // Tab B orbits for 5 s (mouse held, moved every 40 ms); 1 s in, tab A's
  // replica is killed. B's frames are sampled as it goes.
  const box = await b.page.locator('#frame').boundingBox();
  const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
  await b.page.mouse.move(cx - 100, cy);
  await b.page.mouse.down();
  const samples = [];
  let tKill = null;
  const t0 = Date.now();
  for (let i = 0; Date.now() - t0 < 5000; ++i) {
    await b.page.mouse.move(cx - 100 + ((i * 8) % 200), cy);
    samples.push({ t: Date.now(), n: await b.page.evaluate(() => window.vpmViewer.framesReceived) });
    if (tKill === null && Date.now() - t0 > 1000) {
      tKill = Date.now();
      victim.child.kill('SIGKILL');
    }
    await sleep(40);
  }
  await b.page.mouse.up();
  await exited(victim.child);
  const { after: bAfter, longestGap } = framesSince(samples, tKill);
  step(`SIGKILL ${victim.name}: tab B got ${bAfter} frames in the next 4 s, longest gap ` +
       `${longestGap} ms`);
  assert.ok(bAfter >= 5, `tab B got ${bAfter} frames after the kill`);
  assert.ok(longestGap < kMaxGapMs, `tab B stalled for ${longestGap} ms`);
  await settled(b.page, '!h.interactive', 30000);
  assert.equal(await b.page.evaluate(() => window.vpmViewer.session.session_id), b.session,
               'tab B lost its session');

  // Tab A: told why, reopened on a survivor from the volume's source.
  await a.page.waitForFunction(
    (old) => window.vpmViewer.session && window.vpmViewer.session.session_id !== old,
    a.session, { timeout: 60000, polling: 100 });
  await settled(a.page, '!h.interactive', 60000);
  const state = await a.page.evaluate(() => ({
    session: window.vpmViewer.session.session_id, intent: window.vpmViewer.intent,
    messages: window.messages }));
  const survivor = replicaOf(replicas, state.session);
  assert.notEqual(survivor, victim);
  assert.deepEqual(state.intent, { source: volumeSource },
                   'tab A does not reopen from the volume\'s source');
  const said = state.messages.find((m) => /replica behind the balancer went away/.test(m));
  assert.ok(said, `tab A never said why: ${JSON.stringify(state.messages)}`);
  const grey = await canvasGrey(a.page);
  assert.ok(grey.variance > 50, `tab A's frame after the reopen looks blank (${grey.variance})`);
  step(`tab A: "${said}" then reopened as ${state.session} on ${survivor.name}; ` +
       `frame variance ${grey.variance.toFixed(0)}`);
  assert.deepEqual([...a.errors, ...b.errors], [], 'a page threw');
  await browser.close();
}

runScenario('balancer_failover_web', main);
