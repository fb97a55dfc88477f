// The operator GUI's safety display and command answers in a real browser (Debian's chromium,
// headless, playwright-core) against a stack in simulation started by
// services/gui/test/browser_test.cpp (`concert up` with the drill robot, GUI on loopback):
//   * at 1280×800, 1024×768 and 390×844, on every page: the E-STOP fully inside the viewport,
//     nothing over it (elementFromPoint at its centre and near its corners), nothing under it (the
//     scrolling content area never meets it), the page no wider than the screen; a screenshot of
//     every page at every size;
//   * the e-stop engaged from the page: STOPPED on DDS, the full-screen banner, the E-STOP
//     showing it is engaged; released and reset from the `concert` tool: a page opened afterwards
//     shows the software input released, RUNNING, the E-STOP not engaged;
//   * the gateway frozen (SIGSTOP of GUI_PID): the safety badge turns "unknown" (the time it
//     took is printed), and back to RUNNING once it runs again;
//   * a drilling mission the drill service refuses: the page shows the refusal and its reason;
//   * homing asks first: the confirmation dialog, and "no" sends nothing (browser_test.cpp
//     checks the gateway's log holds no customisation command).
// Exit 0 when every check passed. Environment: GUI_URL, GUI_PID, CONCERT_BIN, SHOTS_DIR,
// CHROMIUM (default /usr/bin/chromium).
import { join } from 'node:path';
import { concertTool, environment, runChecks, step } from './harness.mjs';

const env = environment('safety_display_test', ['GUI_URL', 'GUI_PID', 'CONCERT_BIN', 'SHOTS_DIR']);
const url = env.GUI_URL;
const gatewayPid = parseInt(env.GUI_PID, 10);
const concert = env.CONCERT_BIN;
const shots = env.SHOTS_DIR;

const { run, safetyOnDds } = concertTool(concert);

const sizes = [[1280, 800], [1024, 768], [390, 844]];
const pages = ['robot', 'missions', 'transport', 'safety', 'topics'];

/// Where the E-STOP is and what is over or under it, measured in the page.
function estopLayout() {
  const b = document.querySelector('[data-testid=estop]');
  const r = b.getBoundingClientRect();
  const vw = window.innerWidth, vh = window.innerHeight;
  const inside = r.left >= 0 && r.top >= 0 && r.right <= vw && r.bottom <= vh && r.width > 40 && r.height > 40;
  const probes = [[0.5, 0.5], [0.2, 0.2], [0.8, 0.2], [0.2, 0.8], [0.8, 0.8]].map(([fx, fy]) => {
    const x = r.left + fx * r.width, y = r.top + fy * r.height;
    const e = document.elementFromPoint(x, y);
    return { x: Math.round(x), y: Math.round(y), ok: !!e && (e === b || b.contains(e)), what: e ? (e.id || e.tagName) : 'nothing' };
  });
  // The content scrolls in its own area: that area (and the header) never meets the E-STOP, so
  // no content can be under it, however far it is scrolled.
  const meets = (q) => q.left < r.right && r.left < q.right && q.top < r.bottom && r.top < q.bottom;
  const areas = ['main', 'header'].map((sel) => ({ sel, meets: meets(document.querySelector(sel).getBoundingClientRect()) }));
  const overflow = getComputedStyle(document.querySelector('main')).overflowY;
  return {
    rect: { x: Math.round(r.left), y: Math.round(r.top), w: Math.round(r.width), h: Math.round(r.height) },
    inside, probes, areas, overflow,
    pageWidth: document.documentElement.scrollWidth, vw, vh,
  };
}

/// What the safety display shows now, for a failure message.
function safetyShown() {
  const text = (sel) => { const e = document.querySelector(sel); return e ? e.textContent.replace(/\s+/g, ' ').trim() : '(none)'; };
  return `badge "${text('#safety-badge')}" (${document.querySelector('#safety-badge').title || 'fresh'}), ` +
    `link "${text('#link')}", E-STOP engaged=${document.querySelector('[data-testid=estop]').dataset.engaged}, ` +
    `inputs "${text('#estop-inputs')}", causes "${text('#safety-causes')}"`;
}

/// Waits until `fn(arg)` holds in `page`; when it does not, the error says what the safety
/// display showed instead.
async function until(page, what, fn, arg) {
  try {
    await page.waitForFunction(fn, arg);
  } catch (e) {
    throw new Error(`${what}: not seen (${e.message.split('\n')[0]}); the page shows ${await page.evaluate(safetyShown)}`);
  }
}

await runChecks('safety_display_test', async (openPage) => {
  const open = async (w, h) => {
    const page = await openPage(w, h);
    await page.goto(url, { waitUntil: 'domcontentloaded' });
    await page.waitForFunction(() => document.querySelector('[data-testid=model-version]').textContent === 'version 1');
    await until(page, 'safety RUNNING on a new page', () => document.querySelector('#safety-badge').textContent === 'safety: RUNNING');
    return page;
  };
  const tab = async (page, name) => {
    await page.click(`#tabs button[data-page="${name}"]`);
    await page.waitForFunction((n) => document.querySelector('#page-' + n).classList.contains('active'), name);
  };

  // ---- the E-STOP at every size on every page
  for (const [w, h] of sizes) {
    const page = await open(w, h);
    for (const name of pages) {
      await tab(page, name);
      const l = await page.evaluate(estopLayout);
      const bad = [];
      if (!l.inside) bad.push(`not fully on screen (${JSON.stringify(l.rect)} in ${l.vw}×${l.vh})`);
      for (const p of l.probes) if (!p.ok) bad.push(`covered at (${p.x}, ${p.y}) by ${p.what}`);
      for (const a of l.areas) if (a.meets) bad.push(`the ${a.sel} area reaches under it`);
      if (l.overflow !== 'auto' && l.overflow !== 'scroll') bad.push(`the content area does not scroll (${l.overflow})`);
      if (l.pageWidth > l.vw) bad.push(`the page is ${l.pageWidth} px wide on a ${l.vw} px screen`);
      step(`${w}×${h} ${name}: E-STOP at ${JSON.stringify(l.rect)}${bad.length ? ': ' + bad.join('; ') : ', clear'}`);
      if (bad.length) throw new Error(`${w}×${h} ${name}: ${bad.join('; ')}`);
      if (name === 'robot') await page.waitForTimeout(1000);  // the 3D view's first frames, for the screenshot
      await page.screenshot({ path: join(shots, `${name}_${w}x${h}.png`) });
    }
    await page.close();
  }

  // ---- the e-stop from the page: STOPPED everywhere, the banner, the E-STOP engaged
  const page = await open(1280, 800);
  step('e-stop from the page');
  await page.click('[data-testid=estop]');
  step(await safetyOnDds('STOPPED'));
  await until(page, 'safety STOPPED', () => document.querySelector('#safety-badge').textContent === 'safety: STOPPED');
  await page.waitForSelector('[data-testid=stopped-banner]', { state: 'visible' });
  await until(page, 'the E-STOP engaged', () => document.querySelector('[data-testid=estop]').dataset.engaged === 'true');
  step(`banner: ${(await page.textContent('[data-testid=stopped-banner]')).replace(/\s+/g, ' ').trim().slice(0, 160)}`);
  await page.screenshot({ path: join(shots, 'stopped_banner_1280x800.png') });

  // ---- released and reset elsewhere (the tool), then a tablet opened afterwards
  step('release and reset from the concert tool');
  run(['safety', 'estop', '--release', '--reason', 'released by the test']);
  run(['safety', 'reset', '--timeout', '10']);
  step(await safetyOnDds('RUNNING'));
  await until(page, 'safety RUNNING after the reset', () => document.querySelector('#safety-badge').textContent === 'safety: RUNNING');
  await until(page, 'the E-STOP released after the reset', () => document.querySelector('[data-testid=estop]').dataset.engaged === 'false');
  const late = await open(1280, 800);
  await tab(late, 'safety');
  await late.waitForSelector('#estop-inputs li[data-source=software]');
  const input = await late.textContent('#estop-inputs li[data-source=software]');
  const engaged = await late.evaluate(() => document.querySelector('[data-testid=estop]').dataset.engaged);
  step(`a page opened after the release: software input "${input.trim()}", E-STOP engaged=${engaged}`);
  if (!/released/.test(input) || /ENGAGED/.test(input) || engaged === 'true') throw new Error('the late page shows a stale e-stop: ' + input);
  if (await late.isVisible('[data-testid=stopped-banner]')) throw new Error('the late page shows the STOPPED banner while RUNNING');
  await late.close();

  // ---- the gateway frozen: nothing it said stays green
  step(`gateway frozen (SIGSTOP ${gatewayPid})`);
  const frozenAt = Date.now();
  process.kill(gatewayPid, 'SIGSTOP');
  try {
    await page.waitForFunction(() => document.querySelector('#safety-badge').textContent === 'safety: unknown', null, { timeout: 10_000 });
    step(`safety badge "unknown" ${Date.now() - frozenAt} ms after the freeze; link: ${await page.textContent('#link')}`);
    await page.screenshot({ path: join(shots, 'gateway_frozen_1280x800.png') });
  } finally {
    process.kill(gatewayPid, 'SIGCONT');
  }
  await until(page, 'safety RUNNING once the gateway runs again', () => document.querySelector('#safety-badge').textContent === 'safety: RUNNING');
  step('gateway running again: safety RUNNING');

  // ---- a refused mission shows the refusal
  await tab(page, 'missions');
  await page.waitForFunction(() => !document.querySelector('#drill-start').disabled);
  await page.fill('#drill-yaml', 'name: not a mission\nareas: 5\n');
  await page.click('#drill-start');
  await page.waitForFunction(() => /refused/i.test(document.querySelector('[data-testid=drill-result]').textContent));
  step(`drill answer: ${await page.textContent('[data-testid=drill-result]')}`);

  // ---- homing asks first; "no" sends nothing
  await tab(page, 'robot');
  await page.click('#send-homing');
  await page.waitForSelector('#confirm', { state: 'visible' });
  step(`homing asks: ${(await page.textContent('#confirm-text')).trim()}`);
  await page.click('#confirm-no');
  await page.waitForSelector('#confirm', { state: 'hidden' });
});
