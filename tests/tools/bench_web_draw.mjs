// How long the web page takes to draw a result once its bytes have arrived (parse, displacement,
// the first frame with the heat map's colours), in headless Chromium (SwiftShader: the CPU
// draws): each mesh uploaded RUNS times through the file input (auto strength), the page's own
// measurements read from body[data-draw-*-ms]. Prints one line per mesh: faces, the median and
// every run of the drawing time and of its parts, and the server's median run time.
//   usage: node bench_web_draw.mjs URL RUNS MESH...      (scripts/bench-web-draw.sh runs it)
import path from 'node:path';
import { launchBrowser, upload } from './page_steps.mjs';

const [url, runsText, ...meshes] = process.argv.slice(2);
const runs = Number(runsText);
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2; };
const browser = await launchBrowser({ width: 1280, height: 800 });
try {
  for (const mesh of meshes) {
    const rows = [];
    for (let r = 0; r < runs; ++r) {
      const page = await browser.newPage();  // a fresh page each run: nothing cached in the page
      page.setDefaultTimeout(300_000);
      await page.goto(url, { waitUntil: 'load' });
      await page.waitForSelector('body[data-form="ready"]');
      const state = await upload(page, mesh);
      if (state !== 'done') throw new Error(`${path.basename(mesh)}: the run ended ${state}: ${await page.$eval('#error', (e) => e.innerText)}`);
      rows.push(await page.evaluate(() => {
        const d = document.body.dataset;
        const faces = Number(document.getElementById('summary').innerText.match(/([\d,]+) faces/)[1].replaceAll(',', ''));
        return { faces, draw: Number(d.drawMs), parse: Number(d.drawParseMs), measure: Number(d.drawMeasureMs), render: Number(d.drawRenderMs),
                 run: Number(document.getElementById('summary').innerText.match(/run ([\d.]+) s/)[1]) * 1000 };
      }));
      await page.close();
    }
    const m = (k) => Math.round(median(rows.map((row) => row[k])));
    console.log(`${path.basename(mesh)}: ${rows[0].faces} faces · drawing median ${m('draw')} ms of ${runs} ` +
                `(runs ${rows.map((row) => Math.round(row.draw)).join(', ')}) · read ${m('parse')} ms, displacement ${m('measure')} ms, ` +
                `first frame ${m('render')} ms · server run median ${m('run')} ms`);
  }
} finally {
  await browser.close();
}
