// What the gateway trusts about where a request came from, for signing in by
// a link (login CSRF: another site must not send a browser here with the
// attacker's token and have it signed in as the attacker), and where it may
// send a browser back to (never off this origin).

// True for a top-level navigation that the browser says did not come from
// another site: typed or pasted into the address bar, a bookmark
// (`Sec-Fetch-Site: none`), or a link on this gateway's own pages
// (`same-origin`). Browsers since 2020-2023 send these Fetch Metadata
// headers; a request without them (an old browser, a script) cannot be told
// apart from a cross-site one and is refused too.
export function notCrossSiteNavigation(req) {
  const site = req.headers['sec-fetch-site'];
  const mode = req.headers['sec-fetch-mode'];
  const dest = req.headers['sec-fetch-dest'];
  return (site === 'none' || site === 'same-origin') && mode === 'navigate' &&
    (dest === undefined || dest === 'document');
}

// A Location on this origin for `url` (a URL parsed against the gateway):
// its path with every leading slash and backslash but one dropped (a path
// `//evil.example/` or `/\evil.example` would be an address on another
// host), then its query. Anything that still resolves elsewhere gives "/".
export function sameOriginLocation(url) {
  const pathname = `/${url.pathname.replace(/^[/\\]+/, '')}`;
  const query = url.searchParams.toString();
  const location = `${pathname}${query ? `?${query}` : ''}`;
  try {
    const resolved = new URL(location, 'http://gateway.invalid/');
    if (resolved.origin !== 'http://gateway.invalid') return '/';
  } catch {
    return '/';
  }
  return location;
}
