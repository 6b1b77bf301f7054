// Screenshots of web pages in a real headless Chromium (Debian's `chromium` package, installed by
// scripts/install-deps.sh), driven over the DevTools protocol on a pipe (--remote-debugging-pipe: no
// port, no npm package). Chromium's own --screenshot mode is no use for WebGL pages that draw from
// requestAnimationFrame: it runs no animation frames before the shot, so such a page is still blank.
// WebGL runs on SwiftShader (the CPU), so no GPU is needed; every host name resolves to nothing, so a
// page cannot reach the network.
//
//   node chromium_screenshot.mjs [--size WxH] [--wait EXPR] [--report EXPR] [--timeout-ms N] URL=OUT.png...
//
// For each URL: load it, wait until the JavaScript expression EXPR (default document.readyState ===
// 'complete') is truthy, save a PNG of the viewport (WxH CSS pixels, default 640x480, one device pixel
// each) to OUT.png, and print `report: URL: <JSON of the --report expression>`. A URL that differs from
// the one before only in its #fragment is a same-document navigation (the page gets a hashchange event
// and keeps its state: EXPR should check that the page has acted on the new fragment); any other URL
// is loaded afresh.
// Also printed: `request: URL` for every request the page made (tests check none goes to the network),
// `console: ...` and `exception: ...`. Exit status 0 when every shot was taken, 1 when a page did not
// get ready within the time limit (default 60000 ms per page) or Chromium failed, 2 on bad usage.
// CTSURG_CHROMIUM names the browser (default: chromium on the PATH).
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';

const usage = 'usage: node chromium_screenshot.mjs [--size WxH] [--wait EXPR] [--report EXPR] [--timeout-ms N] URL=OUT.png...';
let width = 640, height = 480, timeoutMs = 60000;
let waitExpr = "document.readyState === 'complete'", reportExpr = 'null';
const shots = [];
const args = process.argv.slice(2);
for (let i = 0; i < args.length; ++i) {
  const a = args[i];
  if (a === '--size' && i + 1 < args.length) {
    const m = /^(\d+)x(\d+)$/.exec(args[++i]);
    if (!m) { console.error(usage); process.exit(2); }
    width = Number(m[1]);
    height = Number(m[2]);
  } else if (a === '--wait' && i + 1 < args.length) {
    waitExpr = args[++i];
  } else if (a === '--report' && i + 1 < args.length) {
    reportExpr = args[++i];
  } else if (a === '--timeout-ms' && i + 1 < args.length) {
    timeoutMs = Number(args[++i]);
  } else if (a.includes('=') && !a.startsWith('--')) {
    const at = a.lastIndexOf('=');
    shots.push({ url: a.slice(0, at), out: a.slice(at + 1) });
  } else {
    console.error(usage);
    process.exit(2);
  }
}
if (shots.length === 0) { console.error(usage); process.exit(2); }

const profile = mkdtempSync(path.join(tmpdir(), 'ctsurg-chromium-'));
const chrome = spawn(process.env.CTSURG_CHROMIUM || 'chromium', [
  '--headless', '--no-sandbox', '--remote-debugging-pipe', `--user-data-dir=${profile}`,
  // WebGL 2 on the CPU (SwiftShader through ANGLE); Chromium asks for the "unsafe" flag since 128.
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  // No network: no host name resolves, and nothing runs in the background.
  '--host-resolver-rules=MAP * ~NOTFOUND', '--disable-background-networking', '--disable-component-update',
  '--disable-sync', '--no-first-run', '--no-default-browser-check', '--disable-extensions', '--mute-audio',
  '--hide-scrollbars', `--window-size=${width},${height}`, 'about:blank',
], { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'] });
let stderr = '';
chrome.stderr.on('data', (d) => { stderr = (stderr + d.toString()).slice(-4000); });

// The DevTools protocol over fds 3 (to Chromium) and 4 (from it): JSON messages ending in a NUL.
// Chunks are kept as they come and joined once a message is complete (messages can be megabytes).
let nextId = 0, chunks = [];
const pending = new Map();
const listeners = [];
chrome.stdio[4].on('data', (chunk) => {
  for (let end; (end = chunk.indexOf(0)) >= 0; chunk = chunk.subarray(end + 1)) {
    chunks.push(chunk.subarray(0, end));
    const message = JSON.parse(Buffer.concat(chunks).toString());
    chunks = [];
    if (message.id !== undefined && pending.has(message.id)) {
      const { resolve, reject } = pending.get(message.id);
      pending.delete(message.id);
      if (message.error) reject(new Error(JSON.stringify(message.error)));
      else resolve(message.result);
    } else {
      for (const listener of listeners) listener(message);
    }
  }
  if (chunk.length > 0) chunks.push(chunk);
});
const exited = new Promise((resolve) => chrome.on('exit', resolve));
chrome.stdio[3].on('error', () => {});  // writing after Chromium died: reported by `died` below
function send(method, params = {}, sessionId = undefined) {
  const message = { id: ++nextId, method, params };
  if (sessionId) message.sessionId = sessionId;
  chrome.stdio[3].write(JSON.stringify(message) + '\0');
  return new Promise((resolve, reject) => pending.set(message.id, { resolve, reject }));
}
listeners.push((m) => {
  if (m.method === 'Network.requestWillBeSent') console.log(`request: ${m.params.request.url.slice(0, 200)}`);
  if (m.method === 'Runtime.consoleAPICalled') {
    console.log(`console: ${m.params.args.map((a) => a.value ?? a.description ?? a.type).join(' ').slice(0, 500)}`);
  }
  if (m.method === 'Runtime.exceptionThrown') {
    const d = m.params.exceptionDetails;
    console.log(`exception: ${(d.exception && d.exception.description) || d.text}`.slice(0, 500));
  }
});
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

async function main() {
  const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
  const { sessionId } = await send('Target.attachToTarget', { targetId, flatten: true });
  for (const domain of ['Page', 'Runtime', 'Network']) await send(`${domain}.enable`, {}, sessionId);
  await send('Emulation.setDeviceMetricsOverride', { width, height, deviceScaleFactor: 1, mobile: false }, sessionId);
  let page = null;  // the document shown (its URL without the fragment)
  for (const shot of shots) {
    const withoutFragment = shot.url.split('#')[0];
    // Another document goes through about:blank, so it loads afresh even if it was shown before.
    if (withoutFragment !== page) await send('Page.navigate', { url: 'about:blank' }, sessionId);
    page = withoutFragment;
    await send('Page.navigate', { url: shot.url }, sessionId);
    const start = Date.now();
    for (;;) {
      const r = await send('Runtime.evaluate', { expression: waitExpr, returnByValue: true }, sessionId);
      if (r.result && r.result.value) break;
      if (Date.now() - start > timeoutMs) throw new Error(`${shot.url}: not ready after ${timeoutMs} ms (${waitExpr})`);
      await sleep(100);
    }
    const png = await send('Page.captureScreenshot', { format: 'png' }, sessionId);
    writeFileSync(shot.out, Buffer.from(png.data, 'base64'));
    const report = await send('Runtime.evaluate', { expression: `JSON.stringify(${reportExpr})`, returnByValue: true }, sessionId);
    console.log(`report: ${shot.url.slice(0, 200)}: ${report.result ? report.result.value : 'none'}`);
  }
}

let status = 0;
const died = exited.then((code) => { throw new Error(`chromium exited (${code}): ${stderr}`); });
died.catch(() => {});  // Chromium also exits after a successful run (Browser.close)
try {
  await Promise.race([main(), died]);
} catch (error) {
  console.error(`chromium_screenshot: ${error.message}`);
  status = 1;
}
send('Browser.close').catch(() => {});
if (await Promise.race([exited.then(() => true), sleep(5000).then(() => false)]) === false) chrome.kill('SIGKILL');
rmSync(profile, { recursive: true, force: true });
process.exit(status);
