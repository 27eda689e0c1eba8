// The sign-in page's script: a sign-in link /login#token=TOKEN (what
// scripts/serve.sh prints) signs in by posting the form. The fragment never
// reaches the gateway, a log or a Referer, and it leaves the address bar and
// the history entry (history.replaceState) before anything else runs. The
// gateway marks the form data-link="accept" only for a top-level navigation
// not from another site; a link from elsewhere (another site sending the
// browser here with its own token: login CSRF) is dropped with a message.
const link = /^#token=([^&]*)/.exec(location.hash);
if (link) {
  history.replaceState(null, '', location.pathname + location.search);
  const form = document.getElementById('login');
  let token = '';
  try {
    token = decodeURIComponent(link[1]);
  } catch {
    // not a token: the form stays empty
  }
  if (form.dataset.link === 'accept' && token) {
    document.getElementById('token').value = token;
    form.submit();
  } else {
    const message = document.createElement('div');
    message.id = 'message';
    message.setAttribute('role', 'alert');
    message.dataset.kind = 'error';
    message.textContent = 'That sign-in link was not opened directly (typed, pasted or ' +
      'bookmarked), so it was not used. Sign in with your own token.';
    form.before(message);
  }
}
