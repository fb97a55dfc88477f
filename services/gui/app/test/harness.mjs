// What the GUI's browser scripts share: their environment, a timestamped step log, the `concert`
// tool, safety as DDS reports it, and Debian's chromium (headless, WebGL in software).
import { execFileSync } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { chromium } from 'playwright-core';

/// The named environment variables, or exit 2 naming the missing ones (`script` in the message).
export function environment(script, names) {
  const env = Object.fromEntries(names.map((n) => [n, process.env[n]]));
  const missing = names.filter((n) => !env[n]);
  if (missing.length) {
    console.error(`${script}: set ${missing.join(', ')}`);
    process.exit(2);
  }
  if (env.SHOTS_DIR) mkdirSync(env.SHOTS_DIR, { recursive: true });
  return env;
}

export const step = (what) => console.log(`[${new Date().toISOString().slice(11, 23)}] ${what}`);

/// The `concert` tool at `concert`: run(args) runs it to its end and gives its stdout (throws on a
/// non-zero exit); safetyOnDds(want) polls `concert safety status` until its line starts with
/// `want` (at most `tries` polls).
export function concertTool(concert) {
  const run = (args, timeoutS = 60) => execFileSync(concert, args, { encoding: 'utf8', timeout: timeoutS * 1000 });
  const safetyOnDds = async (want, tries = 40) => {
    let last = '';
    for (let i = 0; i < tries; i++) {
      try { last = run(['safety', 'status', '--timeout', '3']).trim(); } catch (e) { last = String(e.stdout || e.message).trim(); }
      if (last.startsWith('safety: ' + want)) return last;
      await new Promise((r) => setTimeout(r, 250));
    }
    throw new Error(`safety on DDS: expected ${want}, last: ${last}`);
  };
  return { run, safetyOnDds };
}

/// Debian's chromium, headless; WebGL on a machine without a GPU through SwiftShader, Chromium's
/// software renderer. No certificate errors are ignored: HTTPS must verify (gui_https_test
/// gives it the project's CA in $HOME/.pki/nssdb).
function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

/// Runs `checks(openPage)` in a fresh chromium, then exits: 0 when the checks passed and no page
/// raised an error, 1 naming what failed. openPage(width, height) opens a page (60 s per wait)
/// whose errors are collected.
export async function runChecks(script, checks) {
  const browser = await launchChromium();
  const errors = [];
  const openPage = async (width = 1280, height = 800) => {
    const page = await browser.newPage({ viewport: { width, height } });
    page.on('pageerror', (e) => errors.push(String(e)));
    page.setDefaultTimeout(60_000);
    return page;
  };
  let failed = false;
  try {
    await checks(openPage);
    if (errors.length) throw new Error('errors in the page: ' + errors.join('; '));
    step('all checks passed');
  } catch (e) {
    failed = true;
    console.error(`${script}: FAILED: ${e.message}`);
  } finally {
    await browser.close();
  }
  process.exit(failed ? 1 : 0);
}
