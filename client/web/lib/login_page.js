// The sign-in page: a form that posts a user's token to /login. No script
// and no inline style (the Content-Security-Policy allows neither).
const escapeHtml = (s) => String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

export function loginPage(message = '') {
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
  <form id="login" method="post" action="/login">
    <label>Token <input id="token" name="token" type="password" autocomplete="current-password"
      autofocus required maxlength="4096"></label>
    <button id="sign-in" type="submit">Sign in</button>
  </form>
  <p class="help">Sign in with your vpm token. It stays on the gateway: the page gets a session
    cookie only.</p>
</body>
</html>
`;
}
