// A headless Chromium (Debian's `chromium` package, installed by scripts/install-deps.sh) driven over
// the DevTools protocol on a pipe (--remote-debugging-pipe: no port, no npm package), for the browser
// tests (chromium_screenshot.mjs, chromium_live.mjs).
// WebGL runs on SwiftShader (the CPU), so no GPU is needed. No host name resolves, so a page cannot
// reach the network; only the loopback address 127.0.0.1 stays reachable (ctsurg-live's server in
// the live tests).
// CTSURG_CHROMIUM names the browser (default: chromium on the PATH).
//
//   const browser = launchChromium({ width, height });
//   const page = await browser.openPage();              // a tab: { send(method, params), sessionId }
//   browser.listeners.push((message) => ...);           // DevTools events
//   await browser.close();
// `browser.died` rejects when Chromium exits early (race it with the work); runAndExit(browser, name,
// main) does both and exits 0 when main resolved, 1 when it failed or Chromium died.
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';

export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

export function launchChromium({ width = 640, height = 480 } = {}) {
  const profile = mkdtempSync(path.join(tmpdir(), 'ctsurg-chromium-'));
  const chrome = spawn(process.env.CTSURG_CHROMIUM || 'chromium', [
    '--headless', '--no-sandbox', '--remote-debugging-pipe', `--user-data-dir=${profile}`,
    // WebGL 2 on the CPU (SwiftShader through ANGLE); Chromium asks for the "unsafe" flag since 128.
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    // No network: no host name resolves (IP literals included) but the loopback address, and nothing
    // runs in the background.
    '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--no-default-browser-check',
    '--disable-extensions', '--mute-audio', '--hide-scrollbars', `--window-size=${width},${height}`, 'about:blank',
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
  chrome.stdio[3].on('error', () => {});  // writing after Chromium died: reported by `died`
  function send(method, params = {}, sessionId = undefined) {
    const message = { id: ++nextId, method, params };
    if (sessionId) message.sessionId = sessionId;
    chrome.stdio[3].write(JSON.stringify(message) + '\0');
    return new Promise((resolve, reject) => pending.set(message.id, { resolve, reject }));
  }
  const died = exited.then((code) => { throw new Error(`chromium exited (${code}): ${stderr}`); });
  died.catch(() => {});  // Chromium also exits after a successful run (Browser.close)

  return {
    send,
    listeners,
    died,
    // A new tab with Page, Runtime and Network events on, in a width x height viewport.
    async openPage() {
      const { targetId } = await send('Target.createTarget', { url: 'about:blank' });
      const { sessionId } = await send('Target.attachToTarget', { targetId, flatten: true });
      for (const domain of ['Page', 'Runtime', 'Network']) await send(`${domain}.enable`, {}, sessionId);
      await send('Emulation.setDeviceMetricsOverride', { width, height, deviceScaleFactor: 1, mobile: false }, sessionId);
      return {
        sessionId,
        send: (method, params = {}) => send(method, params, sessionId),
        // The value of a JavaScript expression (promises awaited).
        async evaluate(expression) {
          const r = await send('Runtime.evaluate', { expression, returnByValue: true, awaitPromise: true }, sessionId);
          if (r.exceptionDetails) throw new Error(`${expression.slice(0, 80)}: ${r.exceptionDetails.exception?.description ?? r.exceptionDetails.text}`);
          return r.result ? r.result.value : undefined;
        },
        // Waits until `expression` is truthy (polled every 100 ms), at most timeoutMs.
        async waitFor(expression, timeoutMs) {
          const start = Date.now();
          for (;;) {
            const r = await send('Runtime.evaluate', { expression, returnByValue: true }, sessionId);
            if (r.result && r.result.value) return;
            if (Date.now() - start > timeoutMs) throw new Error(`not ready after ${timeoutMs} ms (${expression})`);
            await sleep(100);
          }
        },
      };
    },
    // Closes the browser (killed after 5 s) and removes its profile.
    async close() {
      send('Browser.close').catch(() => {});
      if (await Promise.race([exited.then(() => true), sleep(5000).then(() => false)]) === false) chrome.kill('SIGKILL');
      rmSync(profile, { recursive: true, force: true });
    },
  };
}

// Runs `main` against Chromium dying, closes the browser, exits: 0 when main resolved, else 1 (the
// error printed as `NAME: message`).
export async function runAndExit(browser, name, main) {
  let status = 0;
  try {
    await Promise.race([main(), browser.died]);
  } catch (error) {
    console.error(`${name}: ${error.message}`);
    status = 1;
  }
  await browser.close();
  process.exit(status);
}

// Prints the page's requests, console lines and exceptions as `request: URL`, `console: ...` and
// `exception: ...` lines (tests read them).
export function logPageEvents(message) {
  if (message.method === 'Network.requestWillBeSent') console.log(`request: ${message.params.request.url.slice(0, 200)}`);
  if (message.method === 'Runtime.consoleAPICalled') {
    console.log(`console: ${message.params.args.map((a) => a.value ?? a.description ?? a.type).join(' ').slice(0, 500)}`);
  }
  if (message.method === 'Runtime.exceptionThrown') {
    const d = message.params.exceptionDetails;
    console.log(`exception: ${(d.exception && d.exception.description) || d.text}`.slice(0, 500));
  }
}
