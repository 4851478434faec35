// Drives the web page in headless Chromium (puppeteer-core, Debian's chromium) through what a
// person reads and does after a run, and prints one JSON line of what it saw; the caller
// (tests/integration/web_reading_test.cpp) judges it.
//   usage: node check_web_reading.mjs PLAN.json
// PLAN: {"server": [BINARY, ARGS...] (started here, on a port of its own, so that it can be
//        stopped and started again), "out": DIR, "mesh": FILE (a quick noisy mesh),
//        "override": {"field": "n_normal", "value": "7"}, "invalid": [[FIELD, VALUE], [FIELD, VALUE]],
//        "empty": FILE (0 bytes), "broken": FILE (an OFF the server refuses), "zero": FILE (run with
//        mode none: nothing moves), "slow": {"mesh": FILE, "set": {...}} (a job of a few seconds),
//        "reference": FILE (the clean mesh of "mesh", same faces)}
// Steps, at 1280x800 and 400x800 unless said: (layout) a run's end: the download and the one-line
// summary in view as the page stands, no sideways scroll, no text outside its card, the stage
// timings' bars and units; (what ran) a run with a field overridden: the words shown; (invalid)
// two wrong fields: the focused one below the sticky bar and in view, the error naming the first
// still wrong as each is fixed; (bad files) an empty file and a refused one: the messages;
// (heat, 1280 only) lit colours, the signed mode, a range typed in, a wrong range, a reference
// mesh compared through the server (figures and the deviation map); (keys) the
// view turned, zoomed, panned and framed from the keyboard; (server, 1280 only) the polls of a
// job of a few seconds, then the server killed while a result is shown and Denoise pressed: the
// result kept, the words shown, then the server started again on the same port: the run goes
// through. Every page error is recorded. Exit status 0 when the report was written, 1 when a
// step failed (the report so far, with "failure"). Bounded: 240 s in all.
import { spawn } from 'node:child_process';
import { readFileSync } from 'node:fs';
import net from 'node:net';
import { ENDED, fill, launchBrowser, upload } from './page_steps.mjs';

const TIME_LIMIT_MS = 240_000;
const plan = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const report = { page_errors: [], console: [], phase: 'start', step_ms: {} };
let last = Date.now();
const step = (name) => { const now = Date.now(); report.step_ms[name] = now - last; last = now; };
let server = null;
const killer = setTimeout(() => {
  server?.kill('SIGKILL');
  process.stdout.write(`${JSON.stringify({ ...report, failure: `no result within ${TIME_LIMIT_MS / 1000} s` })}\n`, () => process.exit(1));
}, TIME_LIMIT_MS);

// A free loopback port (the server is started on it, stopped and started again on it).
const freePort = () => new Promise((resolve, reject) => {
  const s = net.createServer();
  s.listen(0, '127.0.0.1', () => { const { port } = s.address(); s.close(() => resolve(port)); });
  s.on('error', reject);
});

async function startServer(port) {
  const [binary, ...args] = plan.server;
  server = spawn(binary, [...args, '--host', '127.0.0.1', '--port', String(port)], { stdio: ['ignore', 'ignore', 'pipe'] });
  server.stderr.on('data', () => {});
  for (let i = 0; i < 100; ++i) {
    const ok = await fetch(`http://127.0.0.1:${port}/readyz`).then((r) => r.ok, () => false);
    if (ok) return;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error('the server did not start');
}

function stopServer() {
  return new Promise((resolve) => {
    if (!server || server.exitCode !== null) return resolve();
    server.once('exit', () => resolve());
    server.kill('SIGKILL');
  });
}

// As the page stands (no scrolling): whether an element is drawn and wholly inside the viewport.
const inView = (page, selector) => page.$eval(selector, (e) => {
  const r = e.getBoundingClientRect();
  const shown = e.getClientRects().length > 0 && r.height > 0;
  return { shown, top: Math.round(r.top), bottom: Math.round(r.bottom), inside: shown && r.top >= 0 && r.bottom <= innerHeight && r.left >= 0 && r.right <= innerWidth };
});

// Sideways scroll, and every piece of text in the result panels, the legend and the action bar
// that reaches outside its card or is cut by its own box (scrollWidth beyond its width).
const layout = (page) => page.evaluate(() => {
  const cards = [...document.querySelectorAll('#results > section, #legend, #actionbar, #compare')].filter((c) => c.getClientRects().length);
  const outside = [];
  for (const card of cards) {
    const box = card.getBoundingClientRect();
    for (const e of card.querySelectorAll('*')) {
      if (!e.getClientRects().length || e.closest('.visually-hidden') || [...e.childNodes].every((n) => n.nodeType !== 3 || !n.textContent.trim())) continue;
      const r = e.getBoundingClientRect();
      const cut = getComputedStyle(e).overflowX !== 'visible' && e.scrollWidth > e.clientWidth + 1;
      if (r.right > box.right + 1 || r.left < box.left - 1 || r.right > innerWidth || cut) outside.push(`${e.tagName.toLowerCase()}${e.id ? `#${e.id}` : ''}: ${e.textContent.trim().slice(0, 40)}`);
    }
  }
  const bars = [...document.querySelectorAll('#timings .bar')].map((b) => b.getBoundingClientRect().width);
  const values = [...document.querySelectorAll('#timings li, #timings tr')].map((row) => row.innerText.replace(/\s+/g, ' ').trim());
  return { scroll_width: document.documentElement.scrollWidth, width: innerWidth, outside, bar_widths: bars, timing_rows: values };
});

// Pixels of the result's half of the canvas: how many are drawn (not background) and the
// spread of their brightness (a lit surface has many levels, an unlit single colour one).
const resultPixels = (page) => page.$eval('#canvas', (c) => {
  const copy = document.createElement('canvas');
  copy.width = c.width;
  copy.height = c.height;
  const ctx = copy.getContext('2d');
  ctx.drawImage(c, 0, 0);
  const { data } = ctx.getImageData(Math.floor(c.width / 2), 0, Math.ceil(c.width / 2), c.height);
  const bg = [0x1d, 0x23, 0x2c];
  const luma = [];
  for (let i = 0; i < data.length; i += 4) {
    if (Math.abs(data[i] - bg[0]) + Math.abs(data[i + 1] - bg[1]) + Math.abs(data[i + 2] - bg[2]) > 24) luma.push(0.2126 * data[i] + 0.7152 * data[i + 1] + 0.0722 * data[i + 2]);
  }
  luma.sort((a, b) => a - b);
  const q = (f) => luma[Math.min(luma.length - 1, Math.floor(f * luma.length))] ?? 0;
  return { drawn: luma.length, luma_p10: q(0.1), luma_p90: q(0.9) };
});

let browser;
try {
  const port = await freePort();
  await startServer(port);
  const url = `http://127.0.0.1:${port}/`;
  browser = await launchBrowser({ width: 1280, height: 800 });
  const page = await browser.newPage();
  page.setDefaultTimeout(60_000);
  page.on('pageerror', (e) => report.page_errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') report.console.push({ text: m.text(), phase: report.phase }); });
  const requests = [];
  page.on('request', (r) => requests.push({ url: r.url(), method: r.method(), at: Date.now() }));
  const open = async (width, height) => {
    await page.setViewport({ width, height });
    await page.goto(url, { waitUntil: 'load' });
    await page.waitForSelector('body[data-form="ready"]');
  };

  report.sizes = [];
  for (const [width, height] of [[1280, 800], [400, 800]]) {
    const v = { width, height };
    report.sizes.push(v);
    // (layout) A run's end, as the page stands then.
    report.phase = `layout:${width}`;
    await open(width, height);
    v.state = await upload(page, plan.mesh);
    v.download = await inView(page, '#download');
    v.result_line = { ...(await inView(page, '#result-line').catch(() => ({ shown: false, inside: false }))),
                      text: await page.$eval('#result-line', (e) => e.textContent).catch(() => '') };
    v.layout = await layout(page);
    await page.screenshot({ path: `${plan.out}/reading-${width}.png`, fullPage: true });

    // (what ran) One field overridden on auto: the words say what ran.
    report.phase = `what-ran:${width}`;
    await fill(page, { [plan.override.field]: plan.override.value });
    await page.click('#run');
    await page.waitForSelector(ENDED);
    v.what_ran = await page.$eval('#reports', (e) => e.innerText);
    v.what_ran_layout = await layout(page);

    // (invalid) Two wrong fields; Denoise; each fixed in turn.
    report.phase = `invalid:${width}`;
    await open(width, height);
    const [[f1, bad1], [f2, bad2]] = plan.invalid;
    await fill(page, { [f1]: bad1, [f2]: bad2 });
    await page.evaluate(() => { document.activeElement?.blur(); window.scrollTo(0, 0); document.querySelector('.panel').scrollTop = 0; });
    await (await page.$('#file')).uploadFile(plan.mesh);
    await page.waitForSelector('body[data-state="invalid"]');
    const placed = (field) => page.evaluate((f) => {
      const row = document.querySelector(`[data-field="${f}"]`), input = row.querySelector('input, select');
      const bar = document.getElementById('actionbar').getBoundingClientRect(), r = input.getBoundingClientRect();
      return { focused: document.activeElement === input, input_top: Math.round(r.top), input_bottom: Math.round(r.bottom), bar_bottom: Math.round(bar.bottom),
               below_bar: r.top >= bar.bottom - 1, in_view: r.top >= 0 && r.bottom <= innerHeight,
               label_below_bar: row.querySelector('label').getBoundingClientRect().top >= bar.bottom - 1 };
    }, field);
    v.invalid = { first: await placed(f1), title: await page.$eval('#error-title', (e) => e.textContent) };
    await page.$eval(`[data-field="${f1}"] input`, (c) => { c.value = ''; c.dispatchEvent(new Event('input', { bubbles: true })); });
    v.invalid.title_after_first_fix = await page.$eval('#error', (e) => (e.hidden ? '' : e.querySelector('#error-title').textContent));
    await page.$eval(`[data-field="${f2}"] input`, (c) => { c.value = ''; c.dispatchEvent(new Event('input', { bubbles: true })); });
    v.invalid.shown_after_both_fixed = await page.$eval('#error', (e) => !e.hidden);

    // (bad files) An empty file, then one the server refuses.
    report.phase = `bad:${width}`;
    await open(width, height);
    const jobsBefore = requests.filter((r) => r.method === 'POST').length;
    v.empty = { state: await upload(page, plan.empty), title: await page.$eval('#error-title', (e) => e.textContent),
                detail: await page.$eval('#error-detail', (e) => e.textContent), error: await inView(page, '#error'),
                sent: requests.filter((r) => r.method === 'POST').length - jobsBefore };
    const brokenState = await upload(page, plan.broken);
    // The server's refusal can come before the browser's own reading of the file has ended.
    await page.waitForFunction(() => {
      const e = document.querySelector('#viewer-empty');
      return e.hidden || !e.textContent.startsWith('Reading ');
    }, { timeout: 15000 }).catch(() => {});
    v.broken = { state: brokenState, title: await page.$eval('#error-title', (e) => e.textContent),
                 canvas_text: await page.$eval('#viewer-empty', (e) => (e.hidden ? '' : e.textContent)) };
  }
  step('sizes');

  // (heat) Lit colours on a run that moved nothing, then on a real run: the signed mode, a range.
  report.phase = 'heat';
  await open(1280, 800);
  await fill(page, { mode: '"none"' });
  await page.$eval('#advanced', (d) => { d.open = false; });
  report.heat = { zero_state: await upload(page, plan.zero) };
  await page.click('input[name=colour][value=heat]');
  report.heat.zero_pixels = await resultPixels(page);
  await page.$eval('#advanced', (d) => { d.open = true; });
  await page.click('#reset');
  await page.$eval('#advanced', (d) => { d.open = false; });
  report.heat.state = await upload(page, plan.mesh);
  await page.click('input[name=colour][value=heat]');
  const legend = () => page.evaluate(() => {
    const max = document.getElementById('legend-max');
    return { min: document.getElementById('legend-min').textContent, max: max.textContent, edge_lengths: Number(max.dataset.edgeLengths),
             bins: (document.getElementById('histogram').dataset.bins ?? '').split(',').map(Number), note: document.getElementById('legend-note').textContent };
  });
  report.heat.distance = await legend();
  report.heat.distance_pixels = await resultPixels(page);
  await page.click('input[name=heat-mode][value=signed]');
  report.heat.signed = await legend();
  await page.screenshot({ path: `${plan.out}/reading-signed.png` });
  await page.click('input[name=heat-mode][value=distance]');
  await page.$eval('#heat-range', (e) => { e.value = ''; });
  await page.type('#heat-range', '0.05');
  await page.keyboard.press('Enter');
  report.heat.ranged = await legend();
  await page.$eval('#heat-range', (e) => { e.value = ''; });
  await page.type('#heat-range', 'abc');
  await page.keyboard.press('Enter');
  report.heat.bad_range = { error: await page.$eval('#heat-range-error', (e) => (e.hidden ? '' : e.textContent)), legend: await legend() };
  // (reference) The clean mesh as the reference: the server's figures for the input and the
  // result, the result's deviation in the heat map.
  await page.$eval('#heat-range', (e) => { e.value = ''; });
  await page.click('#heat-auto');
  await (await page.$('#reference-file')).uploadFile(plan.reference);
  await page.waitForSelector('#reference[data-state="done"], #reference[data-state="failed"]');
  report.reference = await page.evaluate(() => ({
    state: document.getElementById('reference').dataset.state, status: document.getElementById('reference-status').textContent,
    rows: [...document.querySelectorAll('#reference-rows tr')].map((r) => ({ row: r.dataset.row, ev: Number(r.dataset.ev), msae: Number(r.dataset.msae), text: r.innerText })),
    mode: document.getElementById('legend').dataset.mode, title: document.getElementById('legend-title').textContent,
    min: document.getElementById('legend-min').textContent,
  }));
  report.reference.pixels = await resultPixels(page);
  await page.screenshot({ path: `${plan.out}/reading-reference.png` });
  step('heat');

  // (keys) The view from the keyboard.
  report.phase = 'keys';
  await page.click('input[name=colour][value=flat]');
  const view = async () => ({ ...JSON.parse(await page.$eval('#canvas', (c) => c.dataset.view ?? '{}')), pixels: (await resultPixels(page)).drawn });
  await page.focus('#canvas');
  report.keys = { start: await view() };
  for (let i = 0; i < 3; ++i) await page.keyboard.press('ArrowLeft');
  report.keys.left3 = await view();
  await page.keyboard.press('ArrowUp');
  report.keys.up = await view();
  await page.keyboard.press('+');
  await page.keyboard.press('+');
  report.keys.zoomed = await view();
  await page.keyboard.down('Shift');
  await page.keyboard.press('ArrowLeft');
  await page.keyboard.up('Shift');
  report.keys.panned = await view();
  await page.keyboard.press('0');
  report.keys.framed = await view();
  step('keys');

  // (features) The output panel of a glb + Draco result; the strengths side by side, one shown.
  report.phase = 'features';
  await open(1280, 800);
  await fill(page, { 'output.format': '"glb"', 'output.compression': '"draco"' });
  await page.$eval('#advanced', (d) => { d.open = false; });
  report.features = { state: await upload(page, plan.mesh), output_panel: await page.$eval('#output-panel', (e) => e.innerText) };
  await page.click('#compare-run');
  await page.waitForSelector('#compare[data-state="done"]', { timeout: 120_000 });
  report.features.rows = await page.$$eval('#compare-rows tr', (rows) => rows.map((r) => ({
    strength: r.dataset.strength, text: r.cells[1].textContent, mean: Number(r.cells[1].dataset.mean), run_s: Number(r.cells[1].dataset.runS) })));
  await page.click('#compare-rows tr[data-strength="strong"] button');
  await page.waitForFunction(() => /Showing Strong/.test(document.getElementById('stage').textContent));
  report.features.shown = {
    state: await page.$eval('body', (b) => b.dataset.state), download: await page.$eval('#download', (e) => e.textContent),
    strength: await page.$eval('#strength', (e) => e.value), what_ran: await page.$eval('#reports', (e) => e.innerText),
    stale: await page.$eval('#stale', (e) => !e.hidden), line: await page.$eval('#result-line', (e) => e.textContent),
    legend_mean: await page.$eval('#summary', (e) => e.innerText),
  };
  report.features.layout = await layout(page);
  await page.screenshot({ path: `${plan.out}/reading-compare.png`, fullPage: true });
  await page.setViewport({ width: 400, height: 800 });
  report.features.narrow_layout = await layout(page);
  step('features');

  // (server) Polls of a job of a few seconds; the server gone while a result is shown.
  report.phase = 'polls';
  await open(1280, 800);
  await fill(page, plan.slow.set);
  const from = requests.length;
  const t0 = Date.now();
  report.server = { slow_state: await upload(page, plan.slow.mesh) };
  const polls = requests.slice(from).filter((r) => /\/v1\/jobs\/[^/]+\?wait=/.test(r.url));
  report.server.polls = polls.length;
  report.server.poll_seconds = polls.length > 1 ? (polls[polls.length - 1].at - polls[0].at) / 1000 : 0;
  report.server.slow_ms = Date.now() - t0;
  report.phase = 'unreachable';
  await stopServer();
  await page.click('#run');
  await page.waitForFunction(() => /cannot be reached/.test(document.getElementById('error-title').textContent) && !document.getElementById('error').hidden, { timeout: 15_000 });
  report.server.down = {
    state: await page.$eval('body', (b) => b.dataset.state),
    title: await page.$eval('#error-title', (e) => e.textContent), detail: await page.$eval('#error-detail', (e) => e.textContent),
    stage: await page.$eval('#stage', (e) => e.textContent),
    results_shown: await page.$eval('#results', (e) => e.getClientRects().length > 0),
    download_shown: await page.$eval('#download', (e) => e.getClientRects().length > 0),
    pixels: await resultPixels(page),
  };
  await startServer(port);
  report.server.back_state = await page.waitForSelector(ENDED, { timeout: 60_000 }).then(() => page.$eval('body', (b) => b.dataset.state));
  report.server.error_after = await page.$eval('#error', (e) => (e.hidden ? '' : e.innerText));
  step('server');
  report.phase = 'end';
} catch (e) {
  report.failure = String(e?.stack ?? e);
} finally {
  await browser?.close().catch(() => {});
  await stopServer();
  clearTimeout(killer);
}
process.stdout.write(`${JSON.stringify(report)}\n`, () => process.exit(report.failure ? 1 : 0));
