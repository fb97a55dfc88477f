// Small DOM helpers shared by the app's modules, the in-page confirmation dialog and the notice
// (toast). Both sit over `main` only (index.html, style.css): neither can cover the e-stop.

export const $ = (id) => document.getElementById(id);
export const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
export const svgEl = (tag, attrs, text) => {
  const e = document.createElementNS('http://www.w3.org/2000/svg', tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
};
/// A request id for a command: unsigned 32 bits, increasing within this page, distinct across
/// reloads (seeded from the clock).
let nextRequest = (Date.now() % 2000000000) >>> 0;
export const requestId = () => { nextRequest = (nextRequest + 1) % 4294967295 || 1; return nextRequest; };
/// Milliseconds since the page started, monotonic (freshness is measured with it, so a clock
/// change on the tablet cannot make old data look new).
export const now = () => performance.now();

// ---- confirmation dialog (#confirm): an in-page modal, not window.confirm (which blocks the
// page's timers, freshness checks included, while it is open).
let confirmPending = null;
/// Asks `text` with `yes` / `no` labels; resolves true for yes, false for no, Escape, or when
/// another question replaces this one.
export function confirmDialog(text, yes = 'Yes', no = 'Cancel') {
  if (confirmPending) confirmPending(false);
  $('confirm-text').textContent = text;
  $('confirm-yes').textContent = yes;
  $('confirm-no').textContent = no;
  $('confirm').hidden = false;
  $('confirm-no').focus();
  return new Promise((resolve) => {
    confirmPending = (answer) => {
      confirmPending = null;
      $('confirm').hidden = true;
      $('confirm-text').textContent = '';
      resolve(answer);
    };
  });
}
/// Closes an open question as "no" (a new safety stop: the STOPPED banner must not be hidden
/// behind a dialog).
export function cancelConfirm() { if (confirmPending) confirmPending(false); }
export function initConfirm() {
  $('confirm-yes').onclick = () => confirmPending && confirmPending(true);
  $('confirm-no').onclick = () => confirmPending && confirmPending(false);
  document.addEventListener('keydown', (ev) => {
    if (ev.key === 'Escape' && confirmPending) confirmPending(false);
  });
}

// ---- notice (#notice): one short message at a time over the bottom of `main`. It takes no
// taps (style.css): it must never stand between a finger and a button.
let noticeTimer = 0;
/// Shows `text` for `ms`; kind 'bad' is red, 'ok' green, '' neutral.
export function notice(text, kind = '', ms = 6000) {
  const n = $('notice');
  n.textContent = text;
  n.className = 'notice' + (kind ? ' ' + kind : '');
  n.hidden = false;
  clearTimeout(noticeTimer);
  noticeTimer = setTimeout(() => { n.hidden = true; }, ms);
}
