// The safety display, which must not lie: the link's freshness (#link, the grey stale bar over
// main), RUNNING / STOPPED (#safety-badge, #safety-mode, the causes), the e-stop inputs, the
// E-STOP button (always in the safety strip, index.html) and the STOPPED banner with the reset.
//
// A state is shown only while it is fresh: the gateway was heard within 1 s (its heartbeat
// comes every 250 ms) and the safety service's own heartbeat on concert/system/status arrived
// within 1 s. Otherwise everything here says "unknown", in grey. Checked every 200 ms, not only
// when a message arrives (a silent gateway sends none).
import { $, esc, cancelConfirm, notice, now, requestId } from './ui.js';
import { beatAge, statusOf } from './status.js';
import { commandBlock, onAccessChange, signedIn } from './access.js';

const FRESH_MS = 1000;
let link = null;
let safety = null;             // the latest SafetyState
const estops = new Map();      // EStopSource -> the EStopInput with the newest stamp_ns
let bannerMin = false;         // "show the page": the banner is a bar until the next stop
let stopCauses = new Set();    // the causes of the stop the banner shows
let lastPointer = -Infinity;   // when the E-STOP was last pressed by a pointer (now() [ms])
let resetAt = 0;               // when a reset was sent (now() [ms]); 0: none pending

/// Whether the gateway was heard within 1 s.
export const linkFresh = () => link.silentMs() < FRESH_MS;
/// '' when the safety state is fresh, else why it is unknown.
export function safetyStale() {
  if (!link.connected) return 'no connection to the gateway';
  const silent = link.silentMs();
  if (silent >= FRESH_MS) return `no word from the gateway for ${(silent / 1000).toFixed(0)} s`;
  const age = beatAge('safety');
  if (age >= FRESH_MS) return age === Infinity ? 'no heartbeat from the safety service' : `the safety service is silent (${(age / 1000).toFixed(0)} s)`;
  if (!safety) return 'no safety state yet';
  return '';
}

const sourceName = (s) => s.replace('ESTOP_', '').toLowerCase();
/// The e-stop sources the safety state holds engaged (a gateway older than that field: the
/// inputs' newest samples).
function heldEngaged() {
  if (safety && Array.isArray(safety.engaged_inputs)) return safety.engaged_inputs;
  return [...estops.values()].filter((i) => i.engaged).map((i) => i.source);
}
function setHtml(el, html) { if (el.innerHTML !== html) el.innerHTML = html; }
function setText(el, text) { if (el.textContent !== text) el.textContent = text; }
function setClass(el, cls) { if (el.className !== cls) el.className = cls; }

function renderLink() {
  const silent = link.silentMs();
  let text, cls;
  if (!link.connected) { text = link.lastRx ? 'gateway lost: reconnecting' : 'connecting to the gateway'; cls = 'bad'; }
  else if (!link.lastRx) { text = 'connecting to the gateway'; cls = 'unknown'; }
  else if (silent < FRESH_MS) { text = 'gateway connected'; cls = 'ok'; }
  else { text = `gateway silent ${(silent / 1000).toFixed(0)} s`; cls = 'bad'; }
  setText($('link'), text);
  setClass($('link'), 'badge ' + cls);
  // Everything on the pages goes grey while the link is stale: none of it can be trusted.
  const stale = !!link.lastRx && silent >= FRESH_MS;
  $('stale-bar').hidden = !stale;
  if (stale) setText($('stale-bar'), `${text}: what the pages show may be out of date (greyed).`);
  document.querySelector('main').classList.toggle('stale', stale);
}

function renderSafety() {
  const why = safetyStale();
  const fresh = !why;
  const stopped = fresh && safety.mode === 'SAFETY_STOPPED';
  const label = !fresh ? 'unknown' : stopped ? 'STOPPED' : 'RUNNING';
  const cls = !fresh ? 'unknown' : stopped ? 'bad' : 'ok';
  setText($('safety-badge'), 'safety: ' + label);
  setClass($('safety-badge'), 'badge ' + cls);
  $('safety-badge').title = why;
  setText($('safety-mode'), label);
  setClass($('safety-mode'), 'state ' + cls);
  setText($('safety-why'), fresh ? '' : `(${why})`);
  setHtml($('safety-causes'), !fresh ? '' : safety.causes.map((c) => `<li class="fault">${esc(c)}</li>`).join('') +
    (safety.reset_required ? '<li>latched: release every input, then reset</li>' : ''));
  // Every input heard or held engaged, engaged as the safety service says (its state is the
  // authority: an input's own release may never reach this gateway), with the newest sample's
  // reason; "unknown" when the safety state is.
  const held = fresh ? heldEngaged() : [];
  const sources = [...new Set([...estops.keys(), ...held])].sort();
  setHtml($('estop-inputs'), sources.map((source) => {
    const on = held.includes(source);
    const state = !fresh ? 'unknown' : on ? 'ENGAGED' : 'released';
    const c = !fresh ? 'unknown' : on ? 'fault' : '';
    const i = estops.get(source);
    return `<li data-source="${sourceName(source)}" class="${c}">${esc(sourceName(source).replace(/_/g, ' '))}: ` +
      `<b class="input-state">${state}</b> <span class="small">${esc(i && i.engaged === on ? i.reason : '')}</span></li>`;
  }).join('') || '<li class="small">no e-stop input heard yet</li>');
  renderEstop(fresh);
  renderBanner(fresh, stopped);
}

function renderEstop(fresh) {
  const b = $('estop');
  const engaged = fresh && heldEngaged().includes('ESTOP_SOFTWARE');
  const state = !fresh ? 'unknown' : engaged ? 'true' : 'false';
  if (b.dataset.engaged !== state) b.dataset.engaged = state;
  b.classList.toggle('engaged', engaged);
  b.classList.toggle('state-unknown', !fresh);
  b.classList.toggle('needs-signin', !!link.hello && !signedIn());
  setText($('estop-label'), engaged ? 'E-STOP ENGAGED' : 'E-STOP');
  const sub = !link.connected ? 'no gateway' : !link.hello ? 'connecting' : !signedIn() ? 'needs sign-in' : !fresh ? 'state unknown' : '';
  if ($('estop-face').dataset.sub !== sub) $('estop-face').dataset.sub = sub;
  b.setAttribute('aria-label', engaged ? 'E-stop: software stop engaged; press to stop the robot' : 'E-stop: press to stop the robot');
}

function renderBanner(fresh, stopped) {
  const b = $('stopped-banner');
  if (!stopped) {
    // RUNNING ends the stop; "unknown" does not (the banner hides, the strip says unknown).
    if (fresh) { bannerMin = false; stopCauses = new Set(); resetAt = 0; }
    b.hidden = true;
    return;
  }
  // A cause the banner has not shown is a new stop: full size again.
  if (safety.causes.some((c) => !stopCauses.has(c))) {
    bannerMin = false;
    resetAt = 0;
    $('stopped-result').textContent = '';
    cancelConfirm();
  }
  stopCauses = new Set(safety.causes);
  b.hidden = false;
  b.classList.toggle('min', bannerMin);
  setHtml($('stopped-causes'), safety.causes.map((c) => `<li>${esc(c)}</li>`).join(''));
  setText($('stopped-summary'), safety.causes.join('; '));
  const engaged = heldEngaged().map((source) => sourceName(source).replace(/_/g, ' '));
  setText($('stopped-engaged'), engaged.length ? `Still engaged: ${engaged.join(', ')}.` : 'Every e-stop input is released.');
  const block = commandBlock('concert/safety/reset');
  $('reset-wrap').hidden = !!block;
  setText($('stopped-role'), block ? `Reset: ${block}.` : '');
  // A reset that left the robot stopped: say what the safety service answered.
  if (resetAt && now() - resetAt > 1500) {
    const st = statusOf('safety');
    setText($('stopped-result'), `Still stopped after the reset${st && st.message ? ': ' + st.message : ''}.`);
  }
}

function result(text) {
  $('stopped-result').textContent = text;
  $('safety-result').textContent = text;
}

function pressEstop() {
  const note = $('estop-note');
  const who = link.session ? link.session.user : '';
  if (!signedIn()) {
    note.textContent = 'The e-stop needs a signed-in client: sign in, or use the robot\'s own e-stop buttons.';
    notice(note.textContent, 'bad');
  } else {
    note.textContent = 'sending the software e-stop…';
  }
  link.publish('concert/safety/estop', { engaged: true, reason: 'operator GUI' + (who ? ` (${who})` : '') })
    .then(() => {
      note.textContent = `software e-stop sent ${new Date().toLocaleTimeString()}`;
      $('safety-result').textContent = 'software e-stop engaged';
      notice('Software e-stop sent.', 'ok', 3000);  // replaces an older "not sent"
    })
    .catch((e) => {
      note.textContent = signedIn() ? `E-STOP NOT SENT: ${e.message}`
        : `E-STOP NOT SENT: the e-stop needs a signed-in client (gateway: ${e.message}). Sign in, or use the robot's own e-stop buttons.`;
      $('safety-result').textContent = note.textContent;
      notice(note.textContent, 'bad', 10000);
    });
}

async function reset() {
  try {
    result('releasing the software stop…');
    await link.publish('concert/safety/estop', { engaged: false, reason: 'operator GUI reset' });
    await new Promise((r) => setTimeout(r, 300));  // the release reaches safety before the reset
    await link.publish('concert/safety/reset', { request_id: requestId(), reason: 'operator GUI' });
    resetAt = now();
    result('reset sent');
  } catch (e) {
    result('reset not sent: ' + e.message);
  }
}

export function initSafety(l) {
  link = l;
  link.subscribe('concert/safety/state', (s) => { safety = s; renderSafety(); });
  link.subscribe('concert/safety/estop', (e) => {
    const before = estops.get(e.source);
    if (!before || e.stamp_ns >= before.stamp_ns) estops.set(e.source, e);
    renderSafety();
  });
  // Pressing always engages, never releases. A touch fires at pointerdown (no wait for the
  // finger to lift); the click that follows it is ignored, a keyboard's click is not.
  $('estop').addEventListener('pointerdown', (ev) => {
    if (ev.button !== 0) return;
    lastPointer = now();
    pressEstop();
  });
  $('estop').addEventListener('click', () => { if (now() - lastPointer > 1000) pressEstop(); });
  $('reset').onclick = reset;
  $('stopped-hide').onclick = () => { bannerMin = true; renderSafety(); };
  $('stopped-expand').onclick = () => { bannerMin = false; renderSafety(); };
  onAccessChange(renderSafety);
  setInterval(() => { renderLink(); renderSafety(); }, 200);
  renderLink();
  renderSafety();
}
