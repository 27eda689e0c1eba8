// Issue 25, point 9: `/.//evil.example/` redirected off-site for clients
// that take a Location literally. Every redirect of the gateway (the
// ?token= exchange, the sign-in page) stays on the gateway's origin, for
// targets of leading slashes, backslashes and their encodings.
import assert from 'node:assert/strict';

import { request } from '../gateway_client.mjs';

const kTyped = { 'Sec-Fetch-Site': 'none', 'Sec-Fetch-Mode': 'navigate', 'Sec-Fetch-Dest': 'document' };
export const kOffSiteTargets = [
  '/.//evil.example/', '//evil.example/', '///evil.example/', '/\\evil.example/', '/\\/evil.example/',
  '/./\\evil.example/', '/%2F%2Fevil.example/', '/%5C%5Cevil.example/', '/.%2F/evil.example/',
  '/%2e//evil.example/', '/..//evil.example/', '/./././/evil.example/', '/%09/evil.example/'];

export async function run(ctx) {
  const { base } = ctx.gateway;
  let checked = 0;
  for (const target of kOffSiteTargets) {
    for (const [query, headers] of [[`?token=${ctx.tokens.bob}&a=1`, kTyped], ['', {}]]) {
      const r = await request(base, `${target}${query}`, { headers });
      const location = r.headers.location;
      if (location === undefined) continue;
      checked += 1;
      assert.match(location, /^\/(?![/\\])/, `${target} -> Location ${location}`);
      assert.equal(new URL(location, base).origin, base, `${target} -> Location ${location}`);
      assert.ok(!location.includes(ctx.tokens.bob), `${target}: the token stays in the Location`);
    }
  }
  assert.ok(checked >= kOffSiteTargets.length, `only ${checked} redirects to check`);
  return { redirects_checked: checked };
}
