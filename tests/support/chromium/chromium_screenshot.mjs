// Screenshots of web pages in a real headless Chromium (chromium_devtools.mjs: Debian's `chromium`,
// the DevTools protocol on a pipe). Chromium's own --screenshot mode is no use for WebGL pages that draw from
// requestAnimationFrame: it runs no animation frames before the shot, so such a page is still blank.
// WebGL runs on SwiftShader (the CPU), so no GPU is needed; no host name but 127.0.0.1 resolves, so a
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
import { writeFileSync } from 'node:fs';
import { launchChromium, logPageEvents, runAndExit } from './chromium_devtools.mjs';

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

const browser = launchChromium({ width, height });
browser.listeners.push(logPageEvents);

async function main() {
  const page = await browser.openPage();
  let shown = null;  // the document shown (its URL without the fragment)
  for (const shot of shots) {
    const withoutFragment = shot.url.split('#')[0];
    // Another document goes through about:blank, so it loads afresh even if it was shown before.
    if (withoutFragment !== shown) await page.send('Page.navigate', { url: 'about:blank' });
    shown = withoutFragment;
    await page.send('Page.navigate', { url: shot.url });
    await page.waitFor(waitExpr, timeoutMs).catch((e) => { throw new Error(`${shot.url}: ${e.message}`); });
    const png = await page.send('Page.captureScreenshot', { format: 'png' });
    writeFileSync(shot.out, Buffer.from(png.data, 'base64'));
    const report = await page.send('Runtime.evaluate', { expression: `JSON.stringify(${reportExpr})`, returnByValue: true });
    console.log(`report: ${shot.url.slice(0, 200)}: ${report.result ? report.result.value : 'none'}`);
  }
}

await runAndExit(browser, 'chromium_screenshot', main);
