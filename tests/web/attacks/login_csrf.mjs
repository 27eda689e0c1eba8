// Issue 25, point 5 (and 6 of the findings): login CSRF and the token in
// history, in headless Chromium. Another site (a page on 127.0.0.1, the
// gateway on localhost: two sites) sends the browser to the gateway with
// alice's token, by a script navigation and by a clicked link through a
// 302 of its own, as `?token=` and as the `/login#token=` link: the
// browser is not signed in, and no token stays in its address bar. Typed into the
// address bar, both sign in, and afterwards neither the page's address nor
// any entry of the tab's history (Chromium's navigation list, what its
// session files keep) holds the token.
import assert from 'node:assert/strict';
import http from 'node:http';

import { launchBrowser } from '../harness.mjs';
import { request } from '../gateway_client.mjs';

// A page on another site: /link?to=URL navigates by script, /click?to=URL
// is a link to /redirect?to=URL, which answers 302 (the user clicks it).
function startEvilSite() {
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://evil');
    const to = url.searchParams.get('to') ?? '/';
    if (url.pathname === '/redirect') return res.writeHead(302, { Location: to }).end();
    if (url.pathname === '/click') {
      return res.writeHead(200, { 'Content-Type': 'text/html' })
        .end(`<!doctype html><a id="go" href="/redirect?to=${encodeURIComponent(to)}">cats</a>`);
    }
    return res.writeHead(200, { 'Content-Type': 'text/html' })
      .end(`<!doctype html><p>cute cats</p><script>location.href = ${JSON.stringify(to)};</script>`);
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () =>
    resolve({ server, base: `http://127.0.0.1:${server.address().port}` })));
}

async function sessionCookie(context) {
  return (await context.cookies()).find((c) => c.name === 'vpm_session') ?? null;
}

// Every URL of the tab's history (Chromium's own list, over CDP).
async function historyUrls(context, page) {
  const cdp = await context.newCDPSession(page);
  const { entries } = await cdp.send('Page.getNavigationHistory');
  await cdp.detach();
  return entries.map((e) => e.url);
}

async function crossSite(browser, evil, gateway, token) {
  const refused = [];
  for (const how of ['link', 'click']) {
    for (const target of [`/?token=${token}`, `/login#token=${token}`]) {
      const context = await browser.newContext();
      const page = await context.newPage();
      const to = `${gateway}${target}`;
      await page.goto(`${evil}/${how}?to=${encodeURIComponent(to)}`);
      if (how === 'click') await page.click('#go');
      await page.waitForURL((u) => u.origin === gateway, { timeout: 10000 });
      await page.waitForLoadState('load');
      await page.waitForTimeout(300);  // login.js would have posted the form by now
      const what = `${how} to ${target.replace(token, 'TOKEN')}`;
      assert.equal(await sessionCookie(context), null, `${what}: the browser got signed in`);
      assert.ok(!page.url().includes(token), `${what}: the token stays in the address bar`);
      const text = await page.textContent('body');
      assert.match(text, /not opened directly|not from another site/, `${what}: no message`);
      refused.push(what);
      await context.close();
    }
  }
  return refused;
}

async function typed(browser, gateway, token, target, user) {
  const context = await browser.newContext();
  const page = await context.newPage();
  await page.goto(`${gateway}${target}`);
  await page.waitForSelector('#frame', { timeout: 10000 });
  assert.ok(await sessionCookie(context), `${target.replace(token, 'TOKEN')}: not signed in`);
  const who = await page.evaluate(() => fetch('/whoami').then((r) => r.json()));
  assert.deepEqual(who, { user });
  const urls = [page.url(), ...(await historyUrls(context, page))];
  for (const url of urls) {
    assert.ok(!url.includes(token), `${target.replace(token, 'TOKEN')}: the token in ${url.replace(token, 'TOKEN')}`);
  }
  await context.close();
  return urls.map((u) => u.replace(gateway, ''));
}

// Playwright's errors quote the addresses they waited on: the tokens go.
function redacted(e, tokens) {
  let text = String(e?.stack ?? e);
  for (const [user, token] of Object.entries(tokens)) text = text.replaceAll(token, `${user.toUpperCase()}_TOKEN`);
  return new Error(text);
}

export async function run(ctx) {
  try {
    return await attack(ctx);
  } catch (e) {
    throw redacted(e, ctx.tokens);
  }
}

async function attack(ctx) {
  // The browser reaches the gateway as localhost, the attacker as 127.0.0.1.
  const gateway = ctx.gateway.base.replace('127.0.0.1', 'localhost');
  const evil = await startEvilSite();
  const browser = await launchBrowser(ctx.source);
  try {
    const refused = await crossSite(browser, evil.base, gateway, ctx.tokens.alice);
    const viaLink = await typed(browser, gateway, ctx.tokens.alice, `/login#token=${ctx.tokens.alice}`,
                                'alice');
    const viaQuery = await typed(browser, gateway, ctx.tokens.bob, `/?token=${ctx.tokens.bob}`, 'bob');
    // The same ?token= without Fetch Metadata (a script, an old browser): refused.
    const bare = await request(ctx.gateway.base, `/?token=${ctx.tokens.bob}`);
    assert.equal(bare.status, 303);
    assert.equal(bare.headers.location, '/login?link=refused');
    assert.ok(!bare.headers['set-cookie']);
    return { cross_site_refused: refused.length, history_after_link: viaLink,
             history_after_query: viaQuery };
  } finally {
    await browser.close();
    evil.server.close();
  }
}
