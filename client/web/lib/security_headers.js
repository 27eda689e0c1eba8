// Headers on every response of the gateway: a Content-Security-Policy that
// allows only the gateway's own scripts, styles and WebSocket and forbids
// framing (with X-Frame-Options for older browsers), no MIME sniffing, a
// Referer only to the gateway itself (no-referrer would make browsers send
// `Origin: null` with the sign-in form, which the origin check refuses; the
// `?token=` redirect sends no-referrer itself), and HSTS under TLS.
export function securityHeaders({ tls, host }) {
  const ws = host ? ` ${tls ? 'wss' : 'ws'}://${host}` : '';
  const headers = {
    'Content-Security-Policy':
      "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; " +
      `connect-src 'self'${ws}; frame-ancestors 'none'; base-uri 'none'; form-action 'self'`,
    'X-Frame-Options': 'DENY',
    'X-Content-Type-Options': 'nosniff',
    'Referrer-Policy': 'same-origin',
    'Cross-Origin-Opener-Policy': 'same-origin',
    'Cross-Origin-Resource-Policy': 'same-origin',
  };
  if (tls) headers['Strict-Transport-Security'] = 'max-age=31536000';
  return headers;
}
