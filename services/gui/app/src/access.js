// Who this client is and what it may command: the sign-in overlay (#signin: password or a
// one-time pairing code), the header's #whoami and #signout, the session token kept in
// sessionStorage (a reloaded page signs in again with it), and the command gates: every button
// that publishes on a topic is disabled, saying why, when the session's role is below the role
// the gateway's hello gives for that topic (viewer < operator < engineer).
import { $, notice } from './ui.js';

const RANK = { viewer: 0, operator: 1, engineer: 2 };
/// Roles for a gateway whose hello gives none (the gateway's defaults).
const DEFAULT_ROLE = { 'concert/safety/estop': 'viewer', 'concert/model/customisation': 'engineer', 'concert/sim/command': 'engineer' };
const TOKEN_KEY = 'concert.gui.token';

let link = null;
let resuming = false;       // a saved token is being tried: no form yet
let sessionEnds = 0;        // Date.now() when the session expires [ms]; 0: unknown or never
const gates = new Map();    // element -> {topic, extra, why}
const listeners = new Set();

/// The least role that may command `topic` ('' when the gateway takes no commands on it).
export function roleFor(topic) {
  const c = link && link.hello && (link.hello.commands || []).find((x) => x.topic === topic);
  return c ? c.role || DEFAULT_ROLE[topic] || 'operator' : '';
}
/// Why this client may not command `topic` now ('' when it may).
export function commandBlock(topic) {
  if (!link.hello) return 'not connected to the gateway yet';
  const c = (link.hello.commands || []).find((x) => x.topic === topic);
  if (!c) return `the gateway takes no commands on ${topic}`;
  if (c.available === false) return `${topic} is not in this build`;
  const s = link.session;
  if (!s) return 'sign in first';
  const need = roleFor(topic);
  if ((RANK[s.role] ?? -1) < RANK[need]) return `needs the ${need} role (signed in as ${s.role})`;
  return '';
}
export const signedIn = () => !!(link && link.session);

/// Disables `el` (a command button on `topic`) with the reason as its title, and in `why` when
/// given, while the role does not allow it or `extra()` returns a reason. Re-checked by
/// refreshGates() on every session change and by the page's periodic refresh.
export function gate(el, topic, extra = () => '', why = null) {
  gates.set(el, { topic, extra, why });
  applyGate(el);
}
export function applyGate(el) {
  const g = gates.get(el);
  if (!g) return;
  const reason = commandBlock(g.topic) || g.extra() || '';
  el.disabled = !!reason;
  el.title = reason;
  if (g.why) g.why.textContent = reason;
}
export function refreshGates() {
  for (const el of [...gates.keys()]) {
    if (el.isConnected) applyGate(el); else gates.delete(el);
  }
}
/// Calls `fn()` after every session change (signed in, signed out, a new hello).
export function onAccessChange(fn) { listeners.add(fn); }

function changed() {
  render();
  refreshGates();
  for (const fn of listeners) fn();
}

/// #signin-error holds only answers (the gateway's refusal, a missing field), never progress:
/// progress is on the button that was pressed.
function showError(text) { $('signin-error').textContent = text; }
/// The gateway's refusal, and when it is rate-limited, when to try again. Attempts before then
/// still go to the gateway (which answers them unchecked): the form stays usable.
function refused(e, what) {
  let text = `${what} refused: ${e.message}`;
  if (e.retryAfterS > 0) {
    const at = new Date(Date.now() + e.retryAfterS * 1000).toLocaleTimeString();
    text = text.replace(/[.!]$/, '') +
      (/try again/i.test(e.message) ? ` (at ${at}).` : `; try again in ${Math.ceil(e.retryAfterS)} s (at ${at}).`);
  }
  showError(text);
}
/// Shows `busy` on `button` until `promise` settles.
function pressed(button, busy, promise) {
  const label = button.textContent;
  button.textContent = busy;
  const done = () => { button.textContent = label; };
  promise.then(done, done);
  return promise;
}

function render() {
  const auth = link.auth;
  const s = link.session;
  $('whoami').textContent = s ? `${s.user} (${s.role})` : link.hello ? 'not signed in' : '–';
  $('whoami').className = 'badge ' + (s ? 'ok' : 'unknown');
  $('whoami').title = s && sessionEnds ? `the session ends about ${new Date(sessionEnds).toLocaleTimeString()}` : '';
  $('signout').hidden = !(auth.required && s);
  $('signin').hidden = !(link.hello && auth.required && !s && !resuming);
  $('signin-pairing').hidden = !auth.pairing;
}

export function initAccess(l) {
  link = l;
  link.on('hello', () => {
    // A new connection: the gateway forgot this client; sign in again with the saved token.
    const token = sessionStorage.getItem(TOKEN_KEY);
    if (link.auth.required && !link.session && token) {
      resuming = true;
      link.resume(token).catch((e) => {
        sessionStorage.removeItem(TOKEN_KEY);
        showError(`The saved session could not be resumed (${e.message}): sign in again.`);
      }).finally(() => { resuming = false; changed(); });
    }
    changed();
  });
  link.on('session', (s) => {
    if (s.token) sessionStorage.setItem(TOKEN_KEY, s.token);
    sessionEnds = s.expires_in_s ? Date.now() + s.expires_in_s * 1000 : 0;
    showError('');
    $('signin-password').value = '';
    $('signin-code').value = '';
    changed();
  });
  link.on('signedout', (reason) => {
    sessionStorage.removeItem(TOKEN_KEY);
    showError(/^signed out$/i.test(reason) ? 'Signed out.' : `Signed out: ${reason}.`);
    changed();
  });
  link.on('state', changed);

  $('signin-form').addEventListener('submit', (ev) => {
    ev.preventDefault();
    const user = $('signin-user').value.trim(), password = $('signin-password').value;
    if (!user || !password) { showError('Type your user name and password.'); return; }
    pressed($('signin-submit'), 'Signing in…', link.login(user, password)).catch((e) => refused(e, 'Sign-in'));
  });
  $('signin-pair').onclick = () => {
    const code = $('signin-code').value.replace(/\s+/g, '');
    if (!code) { showError('Type the pairing code from the gateway\'s log.'); return; }
    pressed($('signin-pair'), 'Pairing…', link.pair(code)).catch((e) => refused(e, 'Pairing'));
  };
  $('signout').onclick = () => {
    sessionStorage.removeItem(TOKEN_KEY);
    link.logout().catch((e) => notice('sign-out: ' + e.message, 'bad'));
    // Shown signed out at once; the gateway's signed_out or ack follows.
    link.session = null;
    link.authorised = false;
    showError('Signed out.');
    changed();
  };
  render();
}
