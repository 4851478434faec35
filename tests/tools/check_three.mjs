// Loads glTF files in a real browser with three.js GLTFLoader + DRACOLoader and prints one JSON
// line: {"reports": [{file, objects: [...], worldBox} | {file, error}], "browser": "..."}.
// DRACOLoader decodes in Web Workers, which node lacks, so this runs headless Chromium against
// a loopback HTTP server that serves three_loader.html, three.js (node_modules/three) and DIR.
//   usage: node check_three.mjs DIR FILE...      (FILEs are names inside DIR)
// Exit status 0 when every file was reported on (the caller judges the reports), 1 when the
// browser could not run or did not finish within the time limit. Bounded: 60 s, then the
// browser's process group is killed; its profile directory is removed in every case.
import { spawn, execFileSync } from 'node:child_process';
import { createServer } from 'node:http';
import { mkdtempSync, rmSync, createReadStream, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const TIME_LIMIT_MS = 60_000;
const here = path.dirname(fileURLToPath(import.meta.url));
const [dataDir, ...files] = process.argv.slice(2);
if (!dataDir || files.length === 0) {
  console.error('usage: node check_three.mjs DIR FILE...');
  process.exit(2);
}
const roots = { '/three/': path.join(here, 'node_modules', 'three'), '/data/': path.resolve(dataDir) };
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm', '.glb': 'model/gltf-binary',
                '.gltf': 'model/gltf+json', '.bin': 'application/octet-stream' };

const reports = [];
let finish;
const finished = new Promise((resolve) => { finish = resolve; });

// Static files from the two roots only (no path escapes them), the page, and the result sink.
const server = createServer((req, res) => {
  const url = new URL(req.url, 'http://localhost');
  if (req.method === 'POST' && url.pathname === '/result') {
    let body = '';
    req.on('data', (c) => { body += c; });
    req.on('end', () => {
      res.end('ok');
      let report;
      try { report = JSON.parse(body); } catch { report = { fatal: `bad report: ${body.slice(0, 200)}` }; }
      if (report.fatal) finish(report.fatal);
      else if (report.done) finish(null);
      else reports.push(report);
    });
    return;
  }
  let file = null;
  if (url.pathname === '/' || url.pathname === '/three_loader.html') file = path.join(here, 'three_loader.html');
  for (const [prefix, root] of Object.entries(roots)) {
    if (!url.pathname.startsWith(prefix)) continue;
    const candidate = path.join(root, decodeURIComponent(url.pathname.slice(prefix.length)));
    if (candidate.startsWith(root + path.sep)) file = candidate;
  }
  let ok = false;
  try { ok = file !== null && statSync(file).isFile(); } catch { ok = false; }
  if (!ok) {
    res.writeHead(404).end('not found');
    return;
  }
  res.writeHead(200, { 'Content-Type': types[path.extname(file)] ?? 'application/octet-stream', 'Cache-Control': 'no-store' });
  createReadStream(file).pipe(res);
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
const port = server.address().port;

const browserBin = process.env.MDN_CHROMIUM ?? 'chromium';
let version = '';
try { version = execFileSync(browserBin, ['--version'], { encoding: 'utf8', timeout: 20_000 }).trim(); } catch (e) {
  console.error(`cannot run ${browserBin}: ${e.message} (install the Debian package chromium: scripts/deps/apt-test.txt)`);
  server.close();
  process.exit(1);
}

const profile = mkdtempSync(path.join(tmpdir(), 'mdn-chromium-'));
const pageUrl = `http://127.0.0.1:${port}/three_loader.html?files=${files.map(encodeURIComponent).join(',')}`;
// --headless: no display needed. --no-sandbox: CI containers often run as root. The rest keeps
// the browser from reaching the network or doing background work: only loopback is used.
const browser = spawn(browserBin, [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--no-default-browser-check',
  '--disable-background-networking', '--disable-component-update', '--disable-sync', '--disable-extensions',
  '--disable-dev-shm-usage', `--user-data-dir=${profile}`, '--remote-debugging-port=0', pageUrl,
], { detached: true, stdio: ['ignore', 'ignore', 'pipe'] });
let stderr = '';
browser.stderr.on('data', (c) => { stderr = (stderr + c).slice(-4000); });
browser.on('exit', (code, signal) => finish(`browser exited early (code ${code}, signal ${signal})`));
browser.on('error', (e) => finish(`cannot start browser: ${e.message}`));
const timer = setTimeout(() => finish(`no result within ${TIME_LIMIT_MS / 1000} s`), TIME_LIMIT_MS);

const failure = await finished;
clearTimeout(timer);
browser.removeAllListeners('exit');
// The browser's helper processes share its process group: end them all, by the group id.
const exited = browser.exitCode !== null || browser.signalCode !== null
  ? Promise.resolve() : new Promise((resolve) => browser.once('exit', resolve));
try { process.kill(-browser.pid, 'SIGTERM'); } catch { /* already gone */ }
const killer = setTimeout(() => { try { process.kill(-browser.pid, 'SIGKILL'); } catch { /* gone */ } }, 5000);
await exited;
clearTimeout(killer);
server.close();
server.closeAllConnections();
rmSync(profile, { recursive: true, force: true });

if (failure) {
  console.error(`${failure}\n${browserBin} (${version}) stderr tail:\n${stderr}`);
  console.log(JSON.stringify({ browser: version, reports, failure }));
  process.exit(1);
}
console.log(JSON.stringify({ browser: version, reports }));
