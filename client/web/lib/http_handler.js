// Every HTTP request of the gateway but the WebSocket upgrade: the health
// probe, sign-in and sign-out, then the page for signed-in browsers only.
// Nothing a request holds throws out of here: a failure answers 500 (or
// drops that connection) and the gateway carries on.
//
//   GET  /healthz             200 while the gateway runs (no host check: probes)
//   GET  ?token=TOKEN         on a top-level navigation not from another site
//                             (sign_in_link.js): signs in and redirects (303) to
//                             the same path without it; from anywhere else 303 to
//                             /login?link=refused (the token left behind)
//   GET  /login               the sign-in form (a link /login#token=TOKEN fills and
//                             posts it, login.js, on such a navigation only)
//   POST /login               token=TOKEN (form): signs in, 303 to /; 401 with the form
//   POST /logout              ends the sign-in (its tabs close), 303 to /login
//   GET  /whoami              {"user": NAME} or 401
//   POST /upload              a volume file from a signed-in tab (volume_upload.js)
//   GET  anything else        the page (static_files.js) when signed in, else 303 /login
//
// Every request but /healthz must name an allowed host (421 otherwise: DNS
// rebinding); a POST with an Origin must come from an allowed origin (403);
// failed sign-ins are throttled per address (429). Redirects stay on this
// origin. A request but an upload that has not arrived whole within 30 s
// loses its connection (Node's own requestTimeout, which would end an
// upload too, is off: gateway.js).
import { loginPage } from './login_page.js';
import { securityHeaders } from './security_headers.js';
import { notCrossSiteNavigation, sameOriginLocation } from './sign_in_link.js';

const kMaxFormBytes = 8192;
const kFormTimeoutMs = 10000;
const kRequestTimeoutMs = 30000;  // uploads have their own idle limit

// The host name of a Host header ("name:port", "[v6]:port"), lower case;
// null when it does not parse.
export function hostName(header) {
  if (typeof header !== 'string' || header === '' || header.length > 255) return null;
  try {
    return new URL(`http://${header}/`).hostname.toLowerCase().replace(/^\[(.*)\]$/, '$1');
  } catch {
    return null;
  }
}

// The request's path and query, or null when the target does not parse.
function parseTarget(req) {
  try {
    return new URL(req.url, 'http://gateway');
  } catch {
    return null;
  }
}

function readForm(req) {
  return new Promise((resolve, reject) => {
    const type = String(req.headers['content-type'] ?? '').split(';')[0].trim().toLowerCase();
    if (type !== 'application/x-www-form-urlencoded') {
      reject(Object.assign(new Error('a form (application/x-www-form-urlencoded)'), { status: 415 }));
      return;
    }
    const chunks = [];
    let size = 0;
    const timer = setTimeout(() => {
      reject(Object.assign(new Error('the form took too long'), { status: 408 }));
      req.destroy();
    }, kFormTimeoutMs);
    req.on('data', (chunk) => {
      size += chunk.length;
      if (size > kMaxFormBytes) {
        clearTimeout(timer);
        reject(Object.assign(new Error('the form is too large'), { status: 413 }));
        req.destroy();
        return;
      }
      chunks.push(chunk);
    });
    req.on('end', () => {
      clearTimeout(timer);
      resolve(new URLSearchParams(Buffer.concat(chunks).toString('utf8')));
    });
    req.on('error', (e) => {
      clearTimeout(timer);
      reject(e);
    });
  });
}

// options: {signIns, serveFile, allowedHost(req), allowedOrigin(origin),
// tls, log, upload(req, res, signIn): POST /upload, or null: 404}.
export function makeRequestHandler({ signIns, serveFile, allowedHost, allowedOrigin, tls, log,
                                     upload = null }) {
  const address = (req) => req.socket?.remoteAddress ?? 'unknown';

  async function handle(req, res) {
    const host = /^[A-Za-z0-9.:[\]-]{1,255}$/.test(req.headers.host ?? '') ? req.headers.host : '';
    for (const [k, v] of Object.entries(securityHeaders({ tls, host }))) res.setHeader(k, v);
    const text = (status, body, headers = {}) =>
      res.writeHead(status, { 'Content-Type': 'text/plain; charset=utf-8', ...headers })
        .end(`${body}\n`);
    const html = (status, body, headers = {}) =>
      res.writeHead(status, { 'Content-Type': 'text/html; charset=utf-8',
                              'Cache-Control': 'no-store', ...headers }).end(body);
    const redirect = (location, headers = {}) =>
      res.writeHead(303, { Location: location, 'Cache-Control': 'no-store', ...headers }).end();

    const url = parseTarget(req);
    if (url === null) return text(400, 'vpm-web: bad request target');
    if (url.pathname === '/healthz') return text(200, 'ok');
    if (!allowedHost(req)) {
      return text(421, `vpm-web: '${hostName(req.headers.host) ?? ''}' is not an allowed host ` +
                       '(start the gateway with --allowed-host NAME)');
    }
    const origin = req.headers.origin;
    if (req.method === 'POST' && origin !== undefined && !allowedOrigin(origin)) {
      return text(403, 'vpm-web: a form from another site');
    }

    const token = url.searchParams.get('token');
    const signInWith = (tokenGiven, onFailure) => {
      const wait = signIns.throttled(address(req));
      if (wait > 0) {
        return text(429, 'vpm-web: too many failed sign-ins; wait a minute',
                    { 'Retry-After': String(wait) });
      }
      const signIn = signIns.signIn(tokenGiven, address(req));
      if (!signIn) return onFailure();
      log(`signed in: ${signIn.user} from ${address(req)}`);
      return signIn;  // res not answered yet: the caller redirects
    };
    if (token !== null && req.method === 'GET') {
      url.searchParams.delete('token');
      if (!notCrossSiteNavigation(req)) {
        log(`refused a ?token= sign-in from ${address(req)}: not a same-site navigation`);
        // Redirected, so the address bar and history keep no token.
        return redirect('/login?link=refused', { 'Referrer-Policy': 'no-referrer' });
      }
      const signIn = signInWith(token, () =>
        html(401, loginPage('That token is not valid here.')));
      if (signIn?.user) {
        return redirect(sameOriginLocation(url),
                        { 'Set-Cookie': signIns.cookie(signIn), 'Referrer-Policy': 'no-referrer' });
      }
      return undefined;
    }
    if (url.pathname === '/login') {
      if (req.method === 'GET' || req.method === 'HEAD') {
        const message = url.searchParams.get('link') === 'refused'
          ? 'A sign-in link works only when opened directly (typed, pasted or bookmarked), ' +
            'not from another site. Sign in here with your own token.' : '';
        return html(200, loginPage(message, { acceptLink: notCrossSiteNavigation(req) }));
      }
      if (req.method !== 'POST') return text(405, 'method not allowed', { Allow: 'GET, POST' });
      let form;
      try {
        form = await readForm(req);
      } catch (e) {
        return text(e.status ?? 400, `vpm-web: ${e.message}`);
      }
      const signIn = signInWith(form.get('token') ?? '', () =>
        html(401, loginPage('That token is not valid here.')));
      if (signIn?.user) return redirect('/', { 'Set-Cookie': signIns.cookie(signIn) });
      return undefined;
    }
    const signIn = signIns.fromRequest(req);
    if (url.pathname === '/upload' && upload) return upload(req, res, signIn);
    if (url.pathname === '/logout') {
      if (req.method !== 'POST') return text(405, 'method not allowed', { Allow: 'POST' });
      if (signIn) signIns.remove(signIn);
      return redirect('/login', { 'Set-Cookie': signIns.clearedCookie() });
    }
    if (url.pathname === '/whoami') {
      if (!signIn) return text(401, 'vpm-web: not signed in');
      return res.writeHead(200, { 'Content-Type': 'application/json', 'Cache-Control': 'no-store' })
        .end(JSON.stringify({ user: signIn.user }));
    }
    // The stylesheet and login.js are the sign-in page's too.
    if (!signIn && url.pathname !== '/style.css' && url.pathname !== '/login.js') {
      if (req.method === 'GET' || req.method === 'HEAD') return redirect('/login');
      return text(401, 'vpm-web: sign in first (/login)');
    }
    return serveFile(req, res);
  }

  // A request whose body trickles (or never ends) loses its connection, as
  // with Node's requestTimeout; an upload is bounded by volume_upload.js.
  const boundTime = (req) => {
    if (req.method === 'POST' && /^\/upload(\?|$)/.test(req.url ?? '')) return;
    const timer = setTimeout(() => {
      if (!req.complete) req.socket?.destroy();
    }, kRequestTimeoutMs);
    const clear = () => clearTimeout(timer);
    req.once('end', clear);
    req.once('close', clear);
  };

  return (req, res) => {
    req.on('error', () => {});
    res.on('error', () => {});
    boundTime(req);
    const failed = (e) => {
      log(`request ${String(req.method).slice(0, 16)} failed: ${e?.stack ?? e}`);
      if (!res.headersSent) {
        res.writeHead(500, { 'Content-Type': 'text/plain' }).end('vpm-web: internal error\n');
      } else {
        res.destroy();
      }
    };
    try {
      Promise.resolve(handle(req, res)).catch(failed);
    } catch (e) {
      failed(e);
    }
  };
}
