// Steps on the web page shared by its browser drivers (check_web_page.mjs, check_web_reading.mjs):
// Chromium's launch options, filling the parameter form, uploading a file and waiting for the job.
import puppeteer from 'puppeteer-core';

// The page's states after a job: one of these ends a wait.
export const ENDED = 'body[data-state="done"], body[data-state="failed"], body[data-state="cancelled"]';

// Debian's Chromium, headless. --no-sandbox: CI containers run as root. WebGL without a GPU:
// SwiftShader through ANGLE. The rest keeps the browser from doing background work or reaching
// the network; the resolver rule makes every host name but the loopback address unresolvable.
// extra: more command-line switches (the screenshots hide scroll bars).
export function launchBrowser(viewport, extra = []) {
  return puppeteer.launch({
    executablePath: process.env.MDN_CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-quic',
           '--no-first-run', '--no-default-browser-check', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--disable-extensions', '--disable-dev-shm-usage',
           '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1', ...extra],
    defaultViewport: viewport,
  });
}

// Opens the advanced parameters and fills `set` (field -> text, or the JSON of an option).
export async function fill(page, set) {
  await page.$eval('#advanced', (d) => { d.open = true; });
  for (const [field, value] of Object.entries(set ?? {})) {
    const selector = `[data-field="${field}"] input, [data-field="${field}"] select`;
    if (await page.$eval(selector, (c) => c.tagName) === 'SELECT') await page.select(selector, value);
    else {
      await page.$eval(selector, (c) => { c.value = ''; c.dispatchEvent(new Event('input', { bubbles: true })); });
      await page.type(selector, value);
    }
  }
}

// Uploads a file through the file input and waits for the job's end; the state marker is reset
// first so that the previous run's end does not count. Returns the state.
export async function upload(page, file) {
  await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
  await (await page.$('#file')).uploadFile(file);
  await page.waitForSelector(ENDED);
  return page.$eval('body', (b) => b.dataset.state);
}
