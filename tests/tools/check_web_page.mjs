// Drives the server's web page in headless Chromium (Debian's package) with puppeteer-core, as a
// person would, and prints one JSON line of what it saw; the caller (tests/integration/
// web_page_test.cpp) judges it.
//   usage: node check_web_page.mjs PLAN.json
// PLAN: {"url": "http://127.0.0.1:PORT/", "out": DIR, "mesh": FILE, "set": {"field": "value"},
//        "refused": [FILE...], "formats": [FILE...], "drop": FILE,
//        "cancel": {"mesh": FILE, "set": {...}, "then": FILE},
//        "token": "..." (the server wants one), "full": true (screenshots, download, Tab walk)}
// Steps: open the page (typing the token into its dialog if asked), list the form's fields, fill
// `set`, upload `mesh` through the file input, wait for the job, measure the canvas, read the
// legend and the curl and CLI commands; with `full`, take screenshots (side by side,
// displacement, swipe, narrow window), download the result into DIR/download/ and walk the page
// with Tab; then upload each `refused` file and read the error shown, each of `formats` and
// measure the canvas, drop `drop` on the page, run `cancel` (a long job) and press Cancel while
// it runs, then run it again and choose the file `then` while it runs. Every request, console
// message and page error is recorded. Exit status 0 when the report was written, 1 when the
// browser failed or a step timed out (then the report so far, with "failure", is printed).
// Bounded: 120 s in all.
import { readFileSync, mkdirSync, readdirSync, rmSync, statSync } from 'node:fs';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const TIME_LIMIT_MS = 120_000;
const STEP_MS = 60_000;
const plan = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const report = { requests: [], console: [], page_errors: [], failed_requests: [], statuses: [], phase: 'load', step_ms: {} };
const t0 = Date.now();
let last = t0;
const step = (name) => { const now = Date.now(); report.step_ms[name] = now - last; last = now; };
const killer = setTimeout(() => {
  process.stdout.write(`${JSON.stringify({ ...report, failure: `no result within ${TIME_LIMIT_MS / 1000} s` })}\n`,
                       () => process.exit(1));
}, TIME_LIMIT_MS);

// Pixels of each half of the canvas that differ from the background: the meshes were drawn.
const measureCanvas = (page) => page.$eval('#canvas', (c) => {
  const copy = document.createElement('canvas');
  copy.width = c.width;
  copy.height = c.height;
  const ctx = copy.getContext('2d');
  ctx.drawImage(c, 0, 0);
  const { data } = ctx.getImageData(0, 0, c.width, c.height);
  const bg = [0x1d, 0x23, 0x2c];
  const drawn = [0, 0];
  for (let y = 0; y < c.height; ++y) for (let x = 0; x < c.width; ++x) {
    const i = 4 * (y * c.width + x);
    if (Math.abs(data[i] - bg[0]) + Math.abs(data[i + 1] - bg[1]) + Math.abs(data[i + 2] - bg[2]) > 24) ++drawn[x < c.width / 2 ? 0 : 1];
  }
  return { width: c.width, height: c.height, before_pixels: drawn[0], after_pixels: drawn[1] };
});

// In the page: a job runs and its progress has passed 0.
const jobProgressed = () => document.body.dataset.state === 'running' && Number(document.getElementById('progress').value) > 0;

// Uploads a file through the file input and waits for the job's end; the state marker is reset
// first so that the previous run's end does not count.
async function upload(page, file) {
  await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
  await (await page.$('#file')).uploadFile(file);
  await page.waitForSelector('body[data-state="done"], body[data-state="failed"], body[data-state="cancelled"]');
  return page.$eval('body', (b) => b.dataset.state);
}

const executablePath = process.env.MDN_CHROMIUM ?? '/usr/bin/chromium';
let browser;
try {
  browser = await puppeteer.launch({
    executablePath,
    headless: true,
    // --no-sandbox: CI containers run as root. WebGL without a GPU: SwiftShader through ANGLE.
    // The rest keeps the browser from doing background work or reaching the network; the
    // resolver rule makes every host name but the loopback address unresolvable.
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-quic',
           '--no-first-run', '--no-default-browser-check', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--disable-extensions', '--disable-dev-shm-usage',
           '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1'],
    defaultViewport: { width: 1280, height: 720 },
  });
  report.browser = await browser.version();
  step('launch');
  const page = await browser.newPage();
  page.setDefaultTimeout(STEP_MS);
  page.on('request', (r) => report.requests.push(r.url().slice(0, 200)));  // data: URLs can be long
  page.on('response', (r) => report.statuses.push({ url: r.url().slice(0, 200), status: r.status(), phase: report.phase }));
  report.job_ids = [];  // every job the page created, in order
  page.on('response', async (r) => {
    if (r.request().method() === 'POST' && new URL(r.url()).pathname === '/v1/jobs' && r.status() === 202) {
      report.job_ids.push((await r.json()).id);
    }
  });
  page.on('requestfailed', (r) => report.failed_requests.push({ url: r.url().slice(0, 200), error: r.failure()?.errorText, phase: report.phase }));
  page.on('console', (m) => {
    if (['error', 'warn', 'warning'].includes(m.type())) report.console.push({ type: m.type(), text: m.text(), phase: report.phase });
  });
  page.on('pageerror', (e) => report.page_errors.push(String(e)));

  // Open; with auth on, the page asks for the token before it can build its form.
  await page.goto(plan.url, { waitUntil: 'load' });
  if (plan.token) {
    report.phase = 'auth';
    await page.waitForSelector('#token-dialog[open]');
    await page.type('#token', plan.token);
    await page.keyboard.press('Enter');
  }
  await page.waitForSelector('body[data-form="ready"]');
  step('open');
  report.phase = 'form';
  report.form_fields = await page.$$eval('[data-field]', (rows) => rows.map((r) => r.dataset.field));
  for (const [field, value] of Object.entries(plan.set ?? {})) {
    const selector = `[data-field="${field}"] input, [data-field="${field}"] select`;
    if (await page.$eval(selector, (c) => c.tagName) === 'SELECT') await page.select(selector, value);
    else await page.type(selector, value);
  }

  // The job, through the file input.
  report.phase = 'job';
  const started = Date.now();
  report.state = await upload(page, plan.mesh);
  report.job_ms = Date.now() - started;
  step('job');
  report.error_text = await page.$eval('#error', (e) => (e.hidden ? '' : e.innerText));
  if (report.state === 'done') {
    report.canvas = await measureCanvas(page);
    report.legend = await page.$eval('#legend', (l) => ({
      hidden: l.hidden, text: l.innerText,
      edge_lengths: Number(l.querySelector('#legend-max').dataset.edgeLengths),
      model_units: Number(l.querySelector('#legend-max').dataset.modelUnits),
    }));
    report.summary = await page.$eval('#summary', (s) => s.innerText);

    if (plan.full) {
      report.screenshots = [];
      const shot = async (name) => {
        const file = path.join(plan.out, name);
        await page.screenshot({ path: file });
        report.screenshots.push(file);
      };
      // As a person sees the page after the run: nothing focused, the panel at its top.
      await page.evaluate(() => { document.activeElement?.blur(); document.querySelector('.panel').scrollTop = 0; });
      await shot('web-side-by-side.png');
      await page.click('input[name=colour][value=heat]');
      await shot('web-displacement.png');
      await page.click('input[name=layout][value=swipe]');
      await shot('web-swipe.png');
      await page.click('input[name=layout][value=side]');
      await page.evaluate(() => window.scrollTo(0, 0));
      await page.screenshot({ path: path.join(plan.out, 'web-report.png'), fullPage: true });
      await page.setViewport({ width: 420, height: 900 });
      await page.click('#reset-view');
      await shot('web-narrow.png');
      report.narrow_overflow = await page.evaluate(() => document.documentElement.scrollWidth > window.innerWidth);
      await page.setViewport({ width: 1280, height: 720 });
      step('screenshots');
    }

    await page.click('#copy-curl');
    report.curl = await page.$eval('#command', (c) => c.textContent);
    await page.click('#copy-cli');
    report.cli = await page.$eval('#command', (c) => c.textContent);
  }
  if (report.state === 'done' && plan.full) {
    // Download through the browser's own download path.
    const downloads = path.join(plan.out, 'download');
    rmSync(downloads, { recursive: true, force: true });  // an earlier run's file would be renamed "(1)"
    mkdirSync(downloads, { recursive: true });
    const cdp = await browser.target().createCDPSession();
    await cdp.send('Browser.setDownloadBehavior', { behavior: 'allow', downloadPath: downloads, eventsEnabled: true });
    const done = new Promise((resolve) => cdp.on('Browser.downloadProgress', (e) => {
      if (e.state === 'completed' || e.state === 'canceled') resolve(e.state);
    }));
    await page.click('#download');
    let timer;
    report.download_state = await Promise.race([done, new Promise((r) => { timer = setTimeout(() => r('timeout'), STEP_MS); })]);
    clearTimeout(timer);
    step('download');
    report.downloads = readdirSync(downloads).map((f) => path.join(downloads, f)).filter((f) => statSync(f).isFile());


    // Keyboard: what Tab reaches, in order (ids, or name=value for radio buttons).
    await page.focus('body');
    report.tab_order = [];
    for (let i = 0; i < 120; ++i) {
      await page.keyboard.press('Tab');
      const id = await page.evaluate(() => {
        const a = document.activeElement;
        return a === document.body ? '' : a.id || `${a.name}=${a.value}`;
      });
      if (id === report.tab_order[0]) break;
      report.tab_order.push(id);
    }
  }

  step('keyboard');
  // Files the service refuses: the page shows the problem's title and detail.
  report.refused = [];
  for (const file of plan.refused ?? []) {
    report.phase = `refused:${path.basename(file)}`;
    const state = await upload(page, file);
    report.refused.push({
      file: path.basename(file),
      state,
      title: await page.$eval('#error-title', (e) => e.textContent),
      detail: await page.$eval('#error-detail', (e) => e.textContent),
      visible: await page.$eval('#error', (e) => !e.hidden && e.getBoundingClientRect().height > 0),
    });
  }
  step('refused');

  // Every other input format: drawn before and after, with a heat map.
  report.formats = [];
  for (const file of plan.formats ?? []) {
    report.phase = `format:${path.basename(file)}`;
    const state = await upload(page, file);
    report.formats.push({ file: path.basename(file), state, canvas: await measureCanvas(page),
                          legend_hidden: await page.$eval('#legend', (l) => l.hidden),
                          error: await page.$eval('#error', (e) => (e.hidden ? '' : e.innerText)) });
  }
  step('formats');

  // Drag and drop: a file dropped on the page (a synthetic drop event carrying the file's bytes,
  // as the browser builds one for a drag from the desktop) runs like a chosen one.
  if (plan.drop) {
    report.phase = 'drop';
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    await page.evaluate((name, base64) => {
      const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
      const data = new DataTransfer();
      data.items.add(new File([bytes], name));
      const target = document.getElementById('drop');
      for (const type of ['dragenter', 'dragover', 'drop']) {
        target.dispatchEvent(new DragEvent(type, { bubbles: true, cancelable: true, dataTransfer: data }));
      }
    }, path.basename(plan.drop), readFileSync(plan.drop).toString('base64'));
    await page.waitForSelector('body[data-state="done"], body[data-state="failed"], body[data-state="cancelled"]');
    report.drop = { state: await page.$eval('body', (b) => b.dataset.state), file: await page.$eval('#file-name', (e) => e.textContent),
                    canvas: await measureCanvas(page) };
  }

  // Cancel: a long job, its progress while it runs, then the Cancel button.
  if (plan.cancel) {
    report.phase = 'cancel';
    await page.click('#reset');
    for (const [field, value] of Object.entries(plan.cancel.set)) await page.type(`[data-field="${field}"] input`, value);
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    await (await page.$('#file')).uploadFile(plan.cancel.mesh);
    await page.waitForFunction(jobProgressed);
    const running = { state: await page.$eval('body', (b) => b.dataset.state), stage: await page.$eval('#stage', (e) => e.textContent) };
    await page.click('#cancel');
    await page.waitForSelector('body[data-state="cancelled"], body[data-state="done"], body[data-state="failed"]');
    report.cancel = { running, state: await page.$eval('body', (b) => b.dataset.state), stage: await page.$eval('#stage', (e) => e.textContent) };

    // Another file chosen while a job runs: the page cancels that job and runs the new one.
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    await (await page.$('#file')).uploadFile(plan.cancel.mesh);
    await page.waitForFunction(jobProgressed);
    const replaced = report.job_ids.length;
    report.cancel.replaced_state = await upload(page, plan.cancel.then);
    report.cancel.replaced_job = report.job_ids[replaced - 1];
  }
  step('cancel');
  report.phase = 'end';
} catch (e) {
  report.failure = String(e?.stack ?? e);
} finally {
  await browser?.close().catch(() => {});
  clearTimeout(killer);
}
// Exit once the report is written: a plain process.exit() could cut it short on a pipe.
process.stdout.write(`${JSON.stringify(report)}\n`, () => process.exit(report.failure ? 1 : 0));
