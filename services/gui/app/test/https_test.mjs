// The operator GUI over HTTPS with sign-in, in a real browser (Debian's chromium, headless,
// playwright-core) that trusts the project's CA through its NSS database (set up by
// services/gui/test/https_test.cpp, which started `concert up --gui-bind 0.0.0.0 --gui-tls DIR`
// with the drill robot and three users). Checks, with DDS as the judge through the `concert` tool:
//   * the page loads over https://localhost with no certificate error (a page error or a failed
//     load fails the test) and asks to sign in before it shows anything;
//   * viewer: every command button disabled, a mission sent anyway (through the page's link) is
//     refused by the gateway naming the role; the E-STOP stops the robot;
//   * operator: resets the stop, starts a drilling mission (the drill service takes it: RUNNING),
//     aborts it; the E-STOP works;
//   * engineer: hot swaps to the sanding robot from an assembly file (after a confirmation): model
//     version 2; the E-STOP works, and the reset;
//   * 20 wrong passwords from this address: the first ones are answered "wrong password", the
//     later ones "try again in N s" unchecked.
// browser_test's C++ side then checks the gateway's log (each command with its user, the
// viewer's refusal). Environment: GUI_URL (https://localhost:PORT/), CONCERT_BIN,
// CONCERT_SOURCE_DIR, SHOTS_DIR, HOME (the NSS database), CHROMIUM (default /usr/bin/chromium).
import { join } from 'node:path';
import { concertTool, environment, runChecks, step } from './harness.mjs';

const env = environment('https_test', ['GUI_URL', 'CONCERT_BIN', 'CONCERT_SOURCE_DIR', 'SHOTS_DIR']);
const url = env.GUI_URL;
const concert = env.CONCERT_BIN;
const source = env.CONCERT_SOURCE_DIR;
const shots = env.SHOTS_DIR;

const { run, safetyOnDds } = concertTool(concert);

await runChecks('https_test', async (openPage) => {
  const page = await openPage();
  step(`open ${url}`);
  const response = await page.goto(url, { waitUntil: 'domcontentloaded' });
  const tls = await response.securityDetails();
  step(`HTTP ${response.status()} over ${tls && tls.protocol}, certificate of ${tls && tls.subjectName} from ${tls && tls.issuer}`);
  if (!tls) throw new Error('the page did not come over TLS');
  await page.waitForSelector('#signin', { state: 'visible' });
  const shownBefore = await page.evaluate(() => document.querySelector('[data-testid=model-version]').textContent);
  if (/version \d/.test(shownBefore)) throw new Error('the model is shown before sign-in: ' + shownBefore);
  await page.screenshot({ path: join(shots, 'signin_1280x800.png') });

  const signIn = async (user, password) => {
    await page.fill('#signin-user', user);
    await page.fill('#signin-password', password);
    await page.click('#signin-submit');
    await page.waitForFunction((u) => document.querySelector('#whoami').textContent.includes(u), user);
    await page.waitForSelector('#signin', { state: 'hidden' });
    await page.waitForFunction(() => document.querySelector('[data-testid=model-version]').textContent.startsWith('version'));
    step(`signed in: ${await page.textContent('#whoami')}`);
  };
  const signOut = async () => {
    await page.click('#signout');
    await page.waitForSelector('#signin', { state: 'visible' });
  };
  const estop = async (who) => {
    await page.click('[data-testid=estop]');
    step(`${who}'s e-stop: ${await safetyOnDds('STOPPED')}`);
  };
  const reset = async (who) => {
    // The banner's reset (release the software input, then reset).
    await page.waitForSelector('[data-testid=stopped-banner] [data-testid=banner-reset]', { state: 'visible' });
    await page.click('[data-testid=stopped-banner] [data-testid=banner-reset]');
    step(`${who}'s reset: ${await safetyOnDds('RUNNING')}`);
    await page.waitForSelector('[data-testid=stopped-banner]', { state: 'hidden' });
  };

  // ---- viewer
  await signIn('vera', 'viewer-password');
  await page.click('#tabs button[data-page="missions"]');
  if (!(await page.isDisabled('#drill-start'))) throw new Error('a viewer may press "Start drilling"');
  const refusal = await page.evaluate(() => window.concertLink.publish('concert/drill/mission',
    { mission_id: 4242, name: 'viewer mission', yaml: 'areas: []' }).then(() => 'sent', (e) => e.message));
  step(`viewer's mission: ${refusal}`);
  if (!/role viewer may not command/.test(refusal)) throw new Error('the viewer\'s mission was not refused by role: ' + refusal);
  await estop('viewer');
  if (await page.isVisible('[data-testid=stopped-banner] [data-testid=banner-reset]')) {
    if (!(await page.isDisabled('[data-testid=stopped-banner] [data-testid=banner-reset]'))) throw new Error('a viewer may reset');
  }
  await page.screenshot({ path: join(shots, 'viewer_stopped_1280x800.png') });
  await signOut();

  // ---- operator
  await signIn('otto', 'operator-password');
  await reset('operator');
  await page.click('#tabs button[data-page="missions"]');
  await page.waitForFunction(() => !document.querySelector('#drill-start').disabled);
  await page.click('#drill-start');
  await page.waitForFunction(() => /running/i.test(document.querySelector('[data-testid=drill-status]').textContent));
  step(`operator's mission: ${(await page.textContent('[data-testid=drill-status]')).replace(/\s+/g, ' ').slice(0, 120)}`);
  await page.click('#drill-abort');
  await page.waitForFunction(() => /aborted/i.test(document.querySelector('[data-testid=drill-status]').textContent), null, { timeout: 120_000 });
  step('operator aborted the mission');
  await estop('operator');
  await reset('operator');
  await signOut();

  // ---- engineer: hot swap from an assembly file
  await signIn('erin', 'engineer-password');
  await page.click('#tabs button[data-page="robot"]');
  await page.setInputFiles('#swap-file', join(source, 'deploy/demo/sanding_robot.yaml'));
  await page.click('#swap-send');
  await page.waitForSelector('#confirm', { state: 'visible' });
  step(`hot swap asks: ${(await page.textContent('#confirm-text')).trim()}`);
  await page.click('#confirm-yes');
  await page.waitForFunction(() => /accepted/i.test(document.querySelector('#swap-result').textContent), null, { timeout: 90_000 });
  step(`hot swap: ${await page.textContent('#swap-result')}`);
  await page.waitForFunction(() => document.querySelector('[data-testid=model-version]').textContent === 'version 2', null, { timeout: 120_000 });
  step('model version 2 after the engineer\'s hot swap');
  await estop('engineer');
  await reset('engineer');
  await signOut();

  // ---- 20 wrong passwords from this address
  const answers = [];
  for (let i = 0; i < 20; i++) {
    await page.fill('#signin-user', 'otto');
    await page.fill('#signin-password', `wrong-${i}`);
    await page.evaluate(() => { document.querySelector('#signin-error').textContent = ''; });
    await page.click('#signin-submit');
    await page.waitForFunction(() => document.querySelector('#signin-error').textContent.trim() !== '');
    answers.push(await page.textContent('#signin-error'));
  }
  // Checked: the gateway verified the password ("wrong password", from the fifth on with the wait
  // it now imposes); slowed: refused unchecked while the address waits.
  const slowed = answers.filter((a) => /too many failed sign-ins/.test(a)).length;
  const wrong = answers.filter((a) => /wrong password/.test(a)).length;
  step(`20 wrong passwords: ${wrong} checked, ${slowed} slowed; last: ${answers[19]}`);
  if (wrong < 5 || slowed < 10 || wrong + slowed !== 20) throw new Error('sign-in not slowed: ' + answers.join(' | '));
});
