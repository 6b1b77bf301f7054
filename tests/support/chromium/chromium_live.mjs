// A user at ctsurg-live's page, in a real headless Chromium (chromium_devtools.mjs): opens the page,
// drags a grab across the organ with the mouse, switches to the cut tool with its key and draws a cut,
// saves with S, and takes a screenshot before and after. The mouse and keys are real input events
// (Input.dispatchMouseEvent / dispatchKeyEvent), so the page's own handlers do the work.
//
//   node chromium_live.mjs [--size WxH] [--timeout-ms N] [--grab X,Y,Z] [--cut X,Y,Z] URL BEFORE.png AFTER.png
//
// --grab / --cut: LPS points (mm) on the organ where the drags start (the page projects them to the
// screen through window.ctsurgLive.project); by default the organ's points under 40 %, 60 % and 55 %,
// 40 % of the viewport. Each drag goes 60 px right and 30 px up over 1.2 s.
// Prints `live: <JSON>`: the page's state at the end (frames, pictures, latencies, topology versions,
// errors, guard messages, saved), plus the request, console and exception lines of
// chromium_devtools.mjs. Exit status 0 when every step happened, 1 when one did not within the time
// limit (default 60000 ms a step) or Chromium failed, 2 on bad usage.
import { writeFileSync } from 'node:fs';
import { parseArgs } from 'node:util';
import { launchChromium, logPageEvents, runAndExit, sleep } from './chromium_devtools.mjs';

const usage = 'usage: node chromium_live.mjs [--size WxH] [--timeout-ms N] [--grab X,Y,Z] [--cut X,Y,Z] URL BEFORE.png AFTER.png';
const point = (text) => {
  if (text === undefined) return null;
  const p = text.split(',').map(Number);
  return p.length === 3 && p.every(Number.isFinite) ? p : undefined;
};
let options, positional;
try {
  ({ values: options, positionals: positional } = parseArgs({
    allowPositionals: true,
    options: { size: { type: 'string', default: '640x480' }, 'timeout-ms': { type: 'string', default: '60000' },
               grab: { type: 'string' }, cut: { type: 'string' } },
  }));
} catch {
  positional = [];
}
const size = /^(\d+)x(\d+)$/.exec(options?.size ?? '');
let grab = point(options?.grab), cut = point(options?.cut);
const timeoutMs = Number(options?.['timeout-ms']);
if (positional.length !== 3 || !size || grab === undefined || cut === undefined || !(timeoutMs > 0)) {
  console.error(usage);
  process.exit(2);
}
const [width, height] = [Number(size[1]), Number(size[2])];
const [url, beforePng, afterPng] = positional;

const browser = launchChromium({ width, height });
browser.listeners.push(logPageEvents);

async function screenshot(page, file) {
  const png = await page.send('Page.captureScreenshot', { format: 'png' });
  writeFileSync(file, Buffer.from(png.data, 'base64'));
}

// Presses the left button at the screen point of LPS `p`, moves 60 px right and 30 px up in 36 steps
// of 33 ms, releases.
async function drag(page, p) {
  const [x0, y0] = await page.evaluate(`window.ctsurgLive.project(${JSON.stringify(p)})`);
  const hit = await page.evaluate(`window.ctsurgLive.surfacePointAt(${x0}, ${y0})`);
  if (!hit) throw new Error(`the point ${p} is not on the organ on screen (${x0}, ${y0})`);
  const mouse = (type, x, y, extra = {}) => page.send('Input.dispatchMouseEvent', { type, x, y, button: 'left', ...extra });
  await mouse('mouseMoved', x0, y0, { buttons: 0 });
  await mouse('mousePressed', x0, y0, { buttons: 1, clickCount: 1 });
  const steps = 36;
  for (let k = 1; k <= steps; ++k) {
    await mouse('mouseMoved', x0 + (60 * k) / steps, y0 - (30 * k) / steps, { buttons: 1 });
    await sleep(33);
  }
  await mouse('mouseReleased', x0 + 60, y0 - 30, { buttons: 0, clickCount: 1 });
}

async function key(page, letter) {
  const code = `Key${letter.toUpperCase()}`;
  await page.send('Input.dispatchKeyEvent', { type: 'keyDown', key: letter, code, text: letter });
  await page.send('Input.dispatchKeyEvent', { type: 'keyUp', key: letter, code });
}

async function main() {
  const page = await browser.openPage();
  await page.send('Page.navigate', { url });
  await page.waitFor('window.ctsurgLive && window.ctsurgLive.ready', timeoutMs);
  await screenshot(page, beforePng);
  const first = await page.evaluate('({topology: window.ctsurgLive.topologyVersion, time: window.ctsurgLive.status ? window.ctsurgLive.status.time_s : 0})');

  const under = async (fx, fy) => {
    const p = await page.evaluate(`window.ctsurgLive.surfacePointAt(${fx * width}, ${fy * height})`);
    if (!p) throw new Error(`no organ under ${fx * 100} %, ${fy * 100} % of the viewport`);
    return p;
  };
  grab = grab ?? await under(0.4, 0.6);
  cut = cut ?? await under(0.55, 0.4);
  await drag(page, grab);
  // The grab was begun, moved and ended: the page holds no tool and the server's time went on.
  await page.waitFor('window.ctsurgLive.activeToolId === null && window.ctsurgLive.latencies.length > 0', timeoutMs);

  await key(page, 'c');
  await page.waitFor("window.ctsurgLive.tool === 'cut'", timeoutMs);
  await drag(page, cut);
  await page.waitFor(`window.ctsurgLive.topologyVersion !== ${first.topology}`, timeoutMs);

  await key(page, 's');
  await page.waitFor('window.ctsurgLive.saved !== null', timeoutMs);
  await sleep(300);  // a few more pictures of the cut
  await screenshot(page, afterPng);
  const state = await page.evaluate(`(() => {
    const l = window.ctsurgLive;
    return {topologyBefore: ${first.topology}, topologyAfter: l.topologyVersion, framesApplied: l.framesApplied,
            picturesDrawn: l.picturesDrawn, latencies: l.latencies, errors: l.errors, guards: l.guards,
            ended: l.ended, saved: l.saved, closed: l.closed, status: l.status, bytesReceived: l.bytesReceived,
            triangleCount: l.triangleCount};
  })()`);
  console.log(`live: ${JSON.stringify(state)}`);
}

await runAndExit(browser, 'chromium_live', main);
