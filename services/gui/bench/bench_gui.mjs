// What one tablet costs: a headless chromium (playwright-core) keeps the Robot page open on a
// running stack for SECONDS; prints the gateway's CPU time over that window (from
// /proc/PID/stat) and the bytes and messages the page received on its WebSocket.
// Usage: node services/gui/bench/bench_gui.mjs URL GATEWAY_PID [SECONDS=30] [PAGE=robot]
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(new URL('../app/package.json', import.meta.url));
const { chromium } = require('playwright-core');
const [url, pid, seconds = '30', pageName = 'robot'] = process.argv.slice(2);
if (!url || !pid) {
  console.error('usage: bench_gui.mjs URL GATEWAY_PID [SECONDS] [PAGE]');
  process.exit(2);
}
const ticks = () => {
  const f = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return Number(f[11]) + Number(f[12]);  // utime + stime [clock ticks, 100 Hz]
};
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
let bytes = 0, messages = 0, counting = false;
page.on('websocket', (ws) => ws.on('framereceived', (f) => {
  if (!counting) return;
  messages++;
  bytes += typeof f.payload === 'string' ? Buffer.byteLength(f.payload) : f.payload.length;
}));
await page.goto(url);
await page.click(`#tabs button[data-page="${pageName}"]`);
await page.waitForTimeout(3000);
counting = true;
const t0 = ticks(), w0 = Date.now();
await page.waitForTimeout(Number(seconds) * 1000);
const cpu = (ticks() - t0) / 100, wall = (Date.now() - w0) / 1000;
counting = false;
console.log(JSON.stringify({ page: pageName, wall_s: wall, gateway_cpu_s: cpu,
  gateway_cpu_percent: +(100 * cpu / wall).toFixed(1), ws_kB_per_s: +(bytes / wall / 1000).toFixed(1),
  ws_messages_per_s: +(messages / wall).toFixed(1) }));
await browser.close();
