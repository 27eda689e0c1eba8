// The sign-in page: a form that posts a user's token to /login. No inline
// script or style (the Content-Security-Policy allows neither); login.js
// (public/) signs in with a link's fragment (/login#token=TOKEN) when the
// form says it may: data-link="accept" only when the gateway saw a
// top-level navigation not from another site (sign_in_link.js).
const escapeHtml = (s) => String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

export function loginPage(message = '', { acceptLink = false } = {}) {
  return `<!doctype html>
<html lang="en">
<head>
  <meta charset="utf-8">
  <title>vpm viewer: sign in</title>
  <meta name="viewport" content="width=device-width, initial-scale=1">
  <link rel="stylesheet" href="style.css">
</head>
<body>
  <header><h1>vpm viewer</h1></header>
  ${message ? `<div id="message" role="alert" data-kind="error">${escapeHtml(message)}</div>` : ''}
  <form id="login" method="post" action="/login" data-link="${acceptLink ? 'accept' : 'refuse'}">
    <label>Token <input id="token" name="token" type="password" autocomplete="current-password"
      autofocus required maxlength="4096"></label>
    <button id="sign-in" type="submit">Sign in</button>
  </form>
  <p class="help">Sign in with your vpm token. It stays on the gateway: the page gets a session
    cookie only.</p>
  <script src="login.js"></script>
</body>
</html>
`;
}
