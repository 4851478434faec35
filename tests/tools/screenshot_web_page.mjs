// The web page's pictures for docs/ (scripts/web-screenshots.sh runs this): a mesh uploaded
// through the file input with the default (auto) strength, the result side by side at 1280x800,
// the displacement heat map with a picked vertex, and the page at 400x800.
//   usage: node screenshot_web_page.mjs URL MESH OUT_DIR
import path from 'node:path';
import { launchBrowser } from './page_steps.mjs';

const [url, mesh, out] = process.argv.slice(2);
const browser = await launchBrowser({ width: 1280, height: 800 }, ['--hide-scrollbars']);
try {
  const page = await browser.newPage();
  page.setDefaultTimeout(120_000);
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForSelector('body[data-form="ready"]');
  await (await page.$('#file')).uploadFile(mesh);
  await page.waitForSelector('body[data-state="done"], body[data-state="failed"]');
  if (await page.$eval('body', (b) => b.dataset.state) !== 'done') {
    throw new Error(`the run failed: ${await page.$eval('#error', (e) => e.innerText)}`);
  }
  // As a person sees the page between actions: nothing focused or hovered, scrolled to the top.
  const still = async () => {
    await page.mouse.move(0, 0);
    await page.evaluate(() => { document.activeElement?.blur(); window.scrollTo(0, 0); });
  };
  await still();
  await page.screenshot({ path: path.join(out, 'web-page.png') });
  await page.click('input[name=colour][value=heat]');
  const box = await page.$eval('#canvas', (c) => { const r = c.getBoundingClientRect(); return { x: r.left + 0.72 * r.width, y: r.top + 0.45 * r.height }; });
  await page.mouse.click(box.x, box.y);
  await still();
  await page.screenshot({ path: path.join(out, 'web-displacement.png') });
  await page.click('input[name=colour][value=flat]');
  await page.setViewport({ width: 400, height: 800 });
  await page.click('#reset-view');
  await still();
  await page.screenshot({ path: path.join(out, 'web-narrow.png') });
  if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
  console.log(`wrote ${['web-page.png', 'web-displacement.png', 'web-narrow.png'].map((f) => path.join(out, f)).join(', ')}`);
} finally {
  await browser.close();
}
