// Drives the server's web page in headless Chromium (Debian's package) with puppeteer-core, as a
// person would, and prints one JSON line of what it saw; the caller (tests/integration/
// web_page_test.cpp) judges it.
//   usage: node check_web_page.mjs PLAN.json
// PLAN: {"url": "http://127.0.0.1:PORT/", "out": DIR, "mesh": FILE, "set": {"field": "value"},
//        "refused": [FILE...], "formats": [FILE...], "drop": FILE,
//        "cancel": {"mesh": FILE, "set": {...}, "then": FILE},
//        "invalid": {"field": "n_normal", "value": "5000"}, "zero": FILE (a mesh run with mode
//        none: nothing moves), "large": FILE (a 4 MB OFF, run with mode none), "close": {"mesh":
//        FILE, "set": {...}} (a long job, then the page is closed),
//        "token": "..." (the server wants one), "full": true (screenshots, download, Tab walk)}
// Steps: open the page (typing the token into its dialog if asked), list the form's fields, fill
// `set`, upload `mesh` through the file input, wait for the job, measure the canvas, read the
// legend and the curl and CLI commands; with `full`, take screenshots (side by side,
// displacement, swipe, narrow window), download the result into DIR/download/ and walk the page
// with Tab; then upload each `refused` file and read the error shown, each of `formats` and
// measure the canvas, drop `drop` on the page, run `cancel` (a long job) and press Cancel while
// it runs, then run it again and choose the file `then` while it runs. Then: what is in view at
// 1280x800 and 400x800 (status, Cancel, errors), that no panel of an earlier run stays on screen
// (a second file, a failure), an invalid field answered inline, the heat map's rendered colours
// against the legend's (from screenshots), the download of a large OFF result (resource timing),
// and a long job left running as its page is closed. Every request, console message and page
// error is recorded. Exit status 0 when the report was written, 1 when the browser failed or a
// step timed out (then the report so far, with "failure", is printed). Bounded: 240 s in all.
import { readFileSync, mkdirSync, readdirSync, rmSync, statSync } from 'node:fs';
import path from 'node:path';
import { fill, launchBrowser, upload } from './page_steps.mjs';

const TIME_LIMIT_MS = 240_000;
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

// In the page: whether an element is drawn and lies wholly inside the viewport as it stands
// (no scrolling), and the scroll position.
const inView = (page, selector) => page.$eval(selector, (e) => {
  const r = e.getBoundingClientRect();
  const shown = e.getClientRects().length > 0 && r.height > 0 && getComputedStyle(e).visibility !== 'hidden';
  return { shown, top: Math.round(r.top), bottom: Math.round(r.bottom), inside: shown && r.top >= 0 && r.bottom <= innerHeight && r.left >= 0 && r.right <= innerWidth,
           scroll_y: scrollY, panel_scroll: document.querySelector('.panel').scrollTop };
});

// The panels that belong to a result: drawn or not (the hidden attribute must win over CSS).
const resultPanels = (page) => page.evaluate(() => Object.fromEntries(['results', 'legend', 'stale', 'pick-info'].map((id) => {
  const e = document.getElementById(id);
  return [id, e.getClientRects().length > 0];
})));

// Colours of a screenshot of the page, read in the page itself (a data: URL drawn to a 2D canvas),
// against the legend's bar: for pixels inside the result's half of the canvas (3x3 neighbourhoods
// of one colour within 6 levels, so no edge or background blend), the distance (max over R, G, B)
// to the nearest colour of the legend as lit: the heat map colours the lit surface with white
// lights, so a pixel is a legend colour times a brightness in linear RGB (the best brightness
// for each legend colour is fitted). Returns the distribution, the median colour and the median
// position on the legend (0 to 1) of the best-fitting colours.
async function heatColours(page) {
  const png = await page.screenshot({ encoding: 'base64' });
  return page.evaluate(async (data) => {
    const img = new Image();
    img.src = `data:image/png;base64,${data}`;
    await img.decode();
    const shot = document.createElement('canvas');
    shot.width = img.width;
    shot.height = img.height;
    const ctx = shot.getContext('2d', { willReadFrequently: true });
    ctx.drawImage(img, 0, 0);
    const scale = innerWidth / img.width;  // CSS pixels per screenshot pixel
    const bar = document.getElementById('legend-bar');
    const legend = bar.getContext('2d').getImageData(0, 0, bar.width, 1).data;
    const linear = (v) => { const c = v / 255; return c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4; };
    const srgb = (l) => 255 * (l <= 0.0031308 ? 12.92 * l : 1.055 * l ** (1 / 2.4) - 0.055);
    const stops = [];
    for (let k = 0; k < legend.length; k += 4) stops.push([linear(legend[k]), linear(legend[k + 1]), linear(legend[k + 2])]);
    const canvas = document.getElementById('canvas').getBoundingClientRect();
    const x0 = Math.ceil((canvas.left + canvas.width / 2) / scale) + 4, x1 = Math.floor(canvas.right / scale) - 4;
    const y0 = Math.ceil(canvas.top / scale) + 30, y1 = Math.floor(canvas.bottom / scale) - 4;  // below the "After" tag
    const { data: px } = ctx.getImageData(0, 0, img.width, img.height);
    const at = (x, y) => 4 * (y * img.width + x);
    const bg = [0x1d, 0x23, 0x2c];
    const errors = [], colours = [], positions = [];
    for (let y = y0; y < y1; y += 3) for (let x = x0; x < x1; x += 3) {
      const i = at(x, y);
      const c = [px[i], px[i + 1], px[i + 2]];
      if (Math.max(...c.map((v, k) => Math.abs(v - bg[k]))) < 12) continue;
      let flat = true;
      for (let dy = -1; dy <= 1 && flat; ++dy) for (let dx = -1; dx <= 1; ++dx) {
        const j = at(x + dx, y + dy);
        if (Math.max(Math.abs(px[j] - c[0]), Math.abs(px[j + 1] - c[1]), Math.abs(px[j + 2] - c[2])) > 6) { flat = false; break; }
      }
      if (!flat) continue;
      const cl = c.map(linear);
      let best = 255, where = 0;
      stops.forEach((L, k) => {
        const s = (cl[0] * L[0] + cl[1] * L[1] + cl[2] * L[2]) / (L[0] ** 2 + L[1] ** 2 + L[2] ** 2 || 1);
        const e = Math.max(...L.map((l, m) => Math.abs(srgb(Math.min(1, s * l)) - c[m])));
        if (e < best) { best = e; where = k / (stops.length - 1); }
      });
      errors.push(best);
      colours.push(c);
      positions.push(where);
    }
    errors.sort((a, b) => a - b);
    positions.sort((a, b) => a - b);
    const q = (f) => errors[Math.min(errors.length - 1, Math.floor(f * errors.length))] ?? null;
    const byLuma = colours.map((c) => [c[0] + c[1] + c[2], c]).sort((a, b) => a[0] - b[0]);
    return { samples: errors.length, median: q(0.5), p95: q(0.95), max: errors[errors.length - 1] ?? null,
             median_colour: byLuma[Math.floor(byLuma.length / 2)]?.[1] ?? null,
             median_position: positions[Math.floor(positions.length / 2)] ?? null, p95_position: positions[Math.floor(0.95 * positions.length)] ?? null,
             legend_zero: [legend[0], legend[1], legend[2]] };
  }, png);
}

// In the page: a job runs and its progress has passed 0.
const jobProgressed = () => document.body.dataset.state === 'running' && Number(document.getElementById('progress').value) > 0;

let browser;
try {
  browser = await launchBrowser({ width: 1280, height: 720 });
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
  await fill(page, plan.set);

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
      report.heat = await heatColours(page);
      report.histogram = await page.$eval('#histogram', (c) => (c.dataset.bins ?? '').split(',').map(Number));
      // A click on the result: the picked vertex and how far it moved.
      const box = await page.$eval('#canvas', (c) => { const r = c.getBoundingClientRect(); return { x: r.left + 0.75 * r.width, y: r.top + 0.5 * r.height }; });
      await page.mouse.click(box.x, box.y);
      report.pick = await page.$eval('#pick-info', (e) => ({ hidden: e.hidden, text: e.textContent, vertex: e.dataset.vertex, moved: e.dataset.moved }));
      await shot('web-pick.png');
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
      // Keyboard focus is visible: on the file input (hidden behind its drop zone) the zone shows
      // it, on the main action the button itself.
      if (id === 'file' || id === 'run') {
        report.focus_ring = report.focus_ring ?? {};
        report.focus_ring[id] = await page.evaluate((which) => {
          const style = getComputedStyle(which === 'file' ? document.getElementById('drop') : document.activeElement);
          return { style: style.outlineStyle, width: parseFloat(style.outlineWidth) };
        }, id);
      }
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
    await fill(page, plan.cancel.set);
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

  // The action bar in view, at a desktop and a phone size, as the page stands (whatever the
  // form scrolled): a running job's status and Cancel; a refused file's error. No panel of an
  // earlier run stays on screen while another file runs, nor after a failure.
  if (plan.view) {
    report.view = [];
    for (const [width, height] of [[1280, 800], [400, 800]]) {
      report.phase = `view:${width}`;
      await page.setViewport({ width, height });
      await page.goto(plan.url, { waitUntil: 'load' });
      await page.waitForSelector('body[data-form="ready"]');
      const v = { width, height };
      if (width === 1280) {
        v.first_state = await upload(page, plan.mesh);
        v.panels_after_first = await resultPanels(page);
      }
      await fill(page, plan.view.set);
      await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
      await (await page.$('#file')).uploadFile(plan.view.slow);
      await page.waitForFunction(jobProgressed);
      v.running = { stage: await inView(page, '#stage'), cancel: await inView(page, '#cancel'), progress: await inView(page, '#progress') };
      v.panels_while_second_runs = await resultPanels(page);
      await page.click('#cancel');
      await page.waitForSelector('body[data-state="cancelled"], body[data-state="done"], body[data-state="failed"]');
      v.cancelled = { state: await page.$eval('body', (b) => b.dataset.state), stage: await page.$eval('#stage', (e) => e.textContent),
                      error_shown: await page.$eval('#error', (e) => !e.hidden) };
      await page.click('#reset');
      v.refused_state = await upload(page, plan.view.refused);
      v.refused = { error: await inView(page, '#error'), stage: await inView(page, '#stage'), title: await page.$eval('#error-title', (e) => e.textContent) };
      v.panels_after_failure = await resultPanels(page);
      report.view.push(v);
    }
    await page.setViewport({ width: 1280, height: 720 });
    step('view');
  }

  // A wrong field: answered in the action bar within a second, named, marked and focused;
  // nothing is sent. A file chosen meanwhile is not sent either (no endless "Reading...").
  if (plan.invalid) {
    report.phase = 'invalid';
    await page.goto(plan.url, { waitUntil: 'load' });
    await page.waitForSelector('body[data-form="ready"]');
    const jobsBefore = report.job_ids.length;
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    await fill(page, { [plan.invalid.field]: plan.invalid.value });
    await page.evaluate(() => { document.activeElement?.blur(); window.scrollTo(0, 0); });
    let started = Date.now();
    await (await page.$('#file')).uploadFile(plan.mesh);
    await page.waitForSelector('body[data-state="invalid"]', { timeout: 5000 });
    const onChoose = Date.now() - started;
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    started = Date.now();
    await page.click('#run');
    await page.waitForSelector('body[data-state="invalid"]', { timeout: 5000 });
    report.invalid = {
      on_choose_ms: onChoose, on_run_ms: Date.now() - started,
      title: await page.$eval('#error-title', (e) => e.textContent),
      detail: await page.$eval('#error-detail', (e) => e.textContent),
      error: await inView(page, '#error'),
      focused: await page.evaluate(() => document.activeElement?.name ?? ''),
      field_error: await page.$eval(`[data-field="${plan.invalid.field}"] .field-error`, (e) => e.textContent).catch(() => ''),
      jobs_sent: report.job_ids.length - jobsBefore,
    };
    // Fixed: the error goes and the file runs.
    await page.$eval(`[data-field="${plan.invalid.field}"] input`, (c) => { c.value = ''; c.dispatchEvent(new Event('input')); });
    report.invalid.error_after_fix = await page.$eval('#error', (e) => !e.hidden);
    await page.$eval('body', (b) => { b.dataset.state = 'loading'; });
    await page.click('#run');
    await page.waitForSelector('body[data-state="done"], body[data-state="failed"], body[data-state="cancelled"]');
    report.invalid.state_after_fix = await page.$eval('body', (b) => b.dataset.state);
    step('invalid');
  }

  // The heat map of a run that moves nothing (mode none): every vertex at the legend's zero.
  if (plan.zero) {
    report.phase = 'zero';
    await page.click('#reset');
    await fill(page, { mode: '"none"' });
    await page.$eval('#advanced', (d) => { d.open = false; });
    report.zero = { state: await upload(page, plan.zero) };
    await page.click('input[name=colour][value=heat]');
    await page.evaluate(() => { document.activeElement?.blur(); window.scrollTo(0, 0); });
    report.zero.heat = await heatColours(page);
    await page.click('input[name=colour][value=flat]');
    // Another strength: the result on screen is marked out of date; back again, it is not.
    await page.select('#strength', 'strong');
    report.zero.stale_after_change = (await resultPanels(page)).stale;
    await page.select('#strength', 'auto');
    report.zero.stale_after_revert = (await resultPanels(page)).stale;
    step('zero');
  }

  // A 4 MB OFF converted (mode none): how long its result took to come (resource timing).
  if (plan.large) {
    report.phase = 'large';
    report.large = { state: await upload(page, plan.large) };
    report.large.timing = await page.evaluate(() => performance.getEntriesByType('resource')
      .filter((e) => /\/v1\/jobs\/[0-9a-f]+\/result$/.test(e.name)).map((e) => ({
        name: e.name, duration_ms: e.duration, download_ms: e.responseEnd - e.responseStart, wait_ms: e.responseStart - e.requestStart,
        transfer_bytes: e.transferSize, encoded_bytes: e.encodedBodySize, decoded_bytes: e.decodedBodySize })).pop());
    report.large.stage = await page.$eval('#stage', (e) => e.textContent);
    step('large');
  }

  // A long job, then its page closed: the page's keepalive DELETE must reach the server. The
  // caller checks the job's state through the API.
  if (plan.close) {
    report.phase = 'close';
    const other = await browser.newPage();
    other.setDefaultTimeout(STEP_MS);
    let job = null;
    other.on('response', async (r) => {
      if (r.request().method() === 'POST' && new URL(r.url()).pathname === '/v1/jobs' && r.status() === 202) job = (await r.json()).id;
    });
    other.on('pageerror', (e) => report.page_errors.push(String(e)));
    await other.goto(plan.url, { waitUntil: 'load' });
    await other.waitForSelector('body[data-form="ready"]');
    await fill(other, plan.close.set);
    await (await other.$('#file')).uploadFile(plan.close.mesh);
    await other.waitForFunction(jobProgressed);
    report.close = { job, state: await other.$eval('body', (b) => b.dataset.state) };
    report.close.closed_at_ms = Date.now();
    await other.close();
    step('close');
  }
  report.phase = 'end';
} catch (e) {
  report.failure = String(e?.stack ?? e);
} finally {
  await browser?.close().catch(() => {});
  clearTimeout(killer);
}
// Exit once the report is written: a plain process.exit() could cut it short on a pipe.
process.stdout.write(`${JSON.stringify(report)}\n`, () => process.exit(report.failure ? 1 : 0));
