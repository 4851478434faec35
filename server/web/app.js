// The page: choose or drop a mesh, it is denoised as an asynchronous job (POST /v1/jobs, long
// polls for progress, DELETE to cancel), and the input and the result are shown in 3D with the
// job's report. document.body.dataset.state is empty | loading | running | done | failed |
// cancelled (styling, and what the page's tests wait for).
import { ApiError, cancelJob, getJson, jobResult, onTokenNeeded, pollJob, submitJob, token } from './api.js';
import { ParamForm } from './form.js';
import { displacements, formatOf, loadMesh, meanEdgeLength } from './meshes.js';
import { scaleColour, Viewer } from './viewer.js';

const $ = (id) => document.getElementById(id);
const POLL_S = 0.5;  // long-poll window: progress is redrawn at least this often

const state = { file: null, bytes: null, before: null, job: null, result: null, resultName: '', abort: null, started: 0 };
let form, viewer;

function setState(name) { document.body.dataset.state = name; }

function showError(problem) {
  $('error').hidden = !problem;
  if (!problem) return;
  $('error-title').textContent = problem.title ?? 'Error';
  $('error-detail').textContent = problem.detail ?? '';
  form?.showProblemField(problem);
}

function problemOf(e) {
  if (e instanceof ApiError) return e.problem;
  return { title: 'Error', detail: e?.message ?? String(e) };
}

function setStage(text, fraction) {
  $('stage').textContent = text;
  if (fraction === undefined) $('progress').removeAttribute('value');
  else $('progress').value = fraction;
}

const bytesText = (n) => n >= 1 << 20 ? `${(n / (1 << 20)).toFixed(2)} MiB` : n >= 1024 ? `${(n / 1024).toFixed(1)} KiB` : `${n} B`;
const seconds = (s) => `${s.toFixed(s < 10 ? 2 : 1)} s`;
const num = (x) => (Math.abs(x) >= 1000 || Math.abs(x) < 0.01) && x !== 0 ? x.toExponential(2) : String(+x.toPrecision(3));

// ---------------------------------------------------------------- token (auth on)
onTokenNeeded((wrong) => new Promise((resolve) => {
  const dialog = $('token-dialog');
  dialog.querySelector('p').textContent = wrong
    ? 'That token was refused. Enter the token of this server.'
    : 'This server requires a token for its API. It is kept for this tab only.';
  $('token').value = '';
  dialog.addEventListener('close', () => resolve($('token').value.trim() || null), { once: true });
  dialog.showModal();
}));

// ---------------------------------------------------------------- input
async function chooseFile(file) {
  if (!file) return;
  setState('loading');
  setStage(`Reading ${file.name}…`, undefined);
  showError(null);
  state.file = file;
  state.bytes = await file.arrayBuffer();
  $('file-name').textContent = `${file.name} · ${bytesText(file.size)}`;
  state.before = null;
  viewer.setMesh('before', null);
  viewer.setMesh('after', null);
  $('results').hidden = true;
  $('legend').hidden = true;
  try {
    state.before = await loadMesh(state.bytes, formatOf(file.name, state.bytes));
    viewer.setMesh('before', state.before);
    viewer.frame();
    $('viewer-empty').hidden = true;
  } catch (e) {
    // The server is the judge of what it reads: denoise anyway, show the result alone.
    $('viewer-empty').hidden = false;
    $('viewer-empty').textContent = `This browser cannot draw ${file.name} (${e.message}); the server may still read it.`;
  }
  $('run').disabled = false;
  await run();
}

// ---------------------------------------------------------------- the job
async function run() {
  if (!state.file || !form.valid()) return;
  showError(null);
  // A job still running for an earlier file or earlier parameters is not wanted any more.
  const previous = state.job;
  state.abort?.abort();
  if (previous?.running) cancelJob(previous.id).catch(() => {});
  const abort = state.abort = new AbortController();
  const paramsText = form.paramsText();
  state.job = null;
  state.result = null;
  viewer.setMesh('after', null);
  $('results').hidden = true;
  $('legend').hidden = true;
  state.started = performance.now();
  setState('running');
  $('run').disabled = true;
  $('cancel').disabled = false;
  setStage('Uploading…', undefined);
  let job;
  try {
    job = await submitJob(state.file, paramsText, abort.signal);
    state.job = { id: job.id, paramsText, name: state.file.name, running: true };
    while (job.state === 'queued' || job.state === 'running') {
      const stage = job.state === 'queued' ? 'Queued' : `${job.progress.stage || 'running'}`;
      setStage(`${stage} · ${(100 * job.progress.fraction).toFixed(0)} % · ${seconds((performance.now() - state.started) / 1000)}`, job.progress.fraction);
      job = await pollJob(job.id, POLL_S, abort.signal);
    }
    state.job.running = false;
    if (job.state !== 'succeeded') {
      setState(job.state === 'cancelled' ? 'cancelled' : 'failed');
      setStage(job.state === 'cancelled' ? 'Cancelled.' : 'The job failed.', 0);
      if (job.error) showError(job.error);
      return;
    }
    const bytes = await jobResult(job.id);
    if (state.abort === abort) await showResult(job, bytes);  // unless another run took over
  } catch (e) {
    if (e.name === 'AbortError') {
      if (state.abort === abort) {  // Cancel before the job existed: the upload was dropped
        setState('cancelled');
        setStage('Cancelled.', 0);
      }
      return;
    }
    setState('failed');
    setStage('Refused.', 0);
    showError(problemOf(e));
  } finally {
    if (state.abort === abort) {
      $('run').disabled = !state.file;
      $('cancel').disabled = true;
    }
  }
}

async function cancel() {
  if (!state.job) {
    state.abort?.abort();  // still uploading
    return;
  }
  $('cancel').disabled = true;
  setStage('Cancelling…', undefined);
  try {
    await cancelJob(state.job.id);
  } catch (e) {
    showError(problemOf(e));
  }
}

// ---------------------------------------------------------------- the result
async function showResult(job, bytes) {
  const result = job.result;
  const wall = (performance.now() - state.started) / 1000;
  state.result = new Blob([bytes], { type: result.media_type });
  state.resultName = `${state.file.name.replace(/\.[^.]*$/, '')}-denoised.${result.format}`;
  let after = null;
  try {
    after = await loadMesh(bytes, result.format);
  } catch (e) {
    showError({ title: 'Cannot draw the result', detail: e.message });
  }
  viewer.setMesh('after', after);
  if (!state.before) viewer.frame();
  $('viewer-empty').hidden = Boolean(state.before || after);

  // The heat map: distance moved, in mean edge lengths of the input (the unit of the method's
  // noise measures) and in model units. The scale ends at the 99th percentile (outliers aside).
  let legend = null;
  if (state.before && after) {
    const edge = meanEdgeLength(state.before);
    const moved = displacements(state.before, after, edge);
    const sorted = Float32Array.from(moved).sort();
    const top = sorted[Math.min(sorted.length - 1, Math.floor(0.99 * sorted.length))] || sorted[sorted.length - 1] || 0;
    viewer.setHeat(moved.map((d) => (top > 0 ? d / top : 0)));
    legend = { edge, top, max: sorted[sorted.length - 1] ?? 0, mean: moved.reduce((a, b) => a + b, 0) / (moved.length || 1) };
  }
  showLegend(legend);

  $('summary').replaceChildren(...[
    ['Time', `${seconds(wall)} in all · queue ${seconds(job.timings_s.queue_wait)} · run ${seconds(job.timings_s.run)}`],
    ['Input', `${state.file.name} · ${bytesText(job.input_bytes)}`],
    ['Output', `${result.format}${result.compression === 'draco' ? ' (Draco)' : result.compression === 'meshopt' ? ' (meshopt)' : ''} · ${bytesText(result.bytes)}`],
    ['Mesh', `${result.vertices.toLocaleString('en')} vertices · ${result.faces.toLocaleString('en')} faces`],
    ...(legend ? [['Moved', `mean ${num(legend.mean / legend.edge)} · max ${num(legend.max / legend.edge)} edge lengths`]] : []),
    ...result.notes.map((n) => ['Note', n]),
  ].flatMap(([k, v]) => [Object.assign(document.createElement('dt'), { textContent: k }), Object.assign(document.createElement('dd'), { textContent: v })]));
  showReports(result.reports, result.params);
  showTimings(result.timings_ms);
  $('download').textContent = `Download ${state.resultName}`;
  showCommand('curl');
  $('results').hidden = false;
  setStage(`Done in ${seconds(wall)}.`, 1);
  setState('done');
}

function showLegend(legend) {
  $('legend').hidden = !legend;
  if (!legend) return;
  const bar = $('legend-bar'), ctx = bar.getContext('2d');
  for (let x = 0; x < bar.width; ++x) {
    const [r, g, b] = scaleColour(x / (bar.width - 1));
    ctx.fillStyle = `rgb(${255 * r}, ${255 * g}, ${255 * b})`;
    ctx.fillRect(x, 0, 1, bar.height);
  }
  const edges = legend.edge > 0 ? legend.top / legend.edge : 0;
  $('legend-max').textContent = `${num(edges)} edge lengths · ${num(legend.top)} model units`;
  $('legend-min').textContent = '0';
  $('legend-max').dataset.edgeLengths = String(edges);
  $('legend-max').dataset.modelUnits = String(legend.top);
  $('legend-note').textContent = `Distance from each result vertex to the nearest input vertex; mean input edge length ${num(legend.edge)} model units. The scale ends at the 99th percentile.`;
}

function table(rows, head) {
  const t = document.createElement('table');
  if (head) t.createTHead().insertRow().append(...head.map((h) => Object.assign(document.createElement('th'), { textContent: h })));
  const body = t.createTBody();
  for (const r of rows) body.insertRow().append(...r.map((c) => Object.assign(document.createElement('td'), { textContent: c })));
  return t;
}

// Per surface: what auto measured and what ran (chosen or pinned).
function showReports(reports, pinned) {
  const box = $('reports');
  box.replaceChildren();
  reports.forEach((r, i) => {
    const title = document.createElement('h3');
    title.textContent = `${reports.length > 1 ? `Surface ${i + 1} · ` : ''}mode ${r.mode}${r.region_prefilter_applied ? ` · region pre-filter on ${r.region_vertices} vertices` : ''}`;
    // report.params is what ran, in the shape of a manual-mode request; the run's own echo
    // (result.params) holds the fields that were pinned.
    const rows = Object.entries(r.params).filter(([k]) => k !== 'mode')
      .map(([k, v]) => [k, typeof v === 'number' ? num(v) : String(v), r.mode === 'auto' && !(k in pinned) ? 'auto' : 'given']);
    box.append(title, table(rows, ['Parameter', 'Ran with', 'Set by']));
    if (r.measures) box.append(table(Object.entries(r.measures).map(([k, v]) => [k, num(v)]), ['Measured', 'Value']));
  });
}

// The stages in the order they run; any stage the server adds later follows them.
const STAGE_ORDER = ['decode', 'setup', 'measure', 'initial_prefilter', 'region_prefilter', 'anisotropic_prefilter',
                     'normal_filter', 'vertex_update', 'encode'];

function showTimings(ms) {
  const rank = (k) => (STAGE_ORDER.includes(k) ? STAGE_ORDER.indexOf(k) : STAGE_ORDER.length);
  const stages = Object.entries(ms).filter(([k]) => k !== 'denoise').sort(([a], [b]) => rank(a) - rank(b));
  const total = stages.reduce((a, [, v]) => a + v, 0) || 1;
  const t = $('timings');
  t.replaceChildren();
  for (const [name, value] of stages) {
    const row = t.insertRow();
    const bar = document.createElement('span');
    bar.className = 'bar';
    bar.style.width = `${(100 * value / total).toFixed(1)}%`;
    row.append(Object.assign(document.createElement('th'), { textContent: name.replaceAll('_', ' ') }),
               Object.assign(document.createElement('td'), { textContent: `${value.toFixed(1)} ms` }));
    row.insertCell().append(bar);
  }
}

// ---------------------------------------------------------------- download, commands
function download() {
  if (!state.result) return;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(state.result);
  a.download = state.resultName;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 60_000);
}

const shellQuote = (s) => /^[A-Za-z0-9_./:=@%+-]+$/.test(s) ? s : `'${s.replaceAll("'", "'\\''")}'`;

function commandText(kind) {
  const { name, paramsText } = state.job;
  const out = state.resultName;
  if (kind === 'cli') {
    return ['meshdenoise', shellQuote(name), shellQuote(out), ...(paramsText === '{}' ? [] : ['--params', shellQuote(paramsText)])].join(' ');
  }
  const auth = token() ? ['-H "Authorization: Bearer $MDN_TOKEN"'] : [];  // the token stays out of the text
  return ['curl -sS --fail-with-body', ...auth, '-F', shellQuote(`mesh=@${name};type=application/octet-stream`),
          '-F', shellQuote(`params=${paramsText}`), shellQuote(`${location.origin}/v1/denoise`), '-o', shellQuote(out)].join(' ');
}

async function showCommand(kind, copy = false) {
  if (!state.job) return;
  const text = commandText(kind);
  $('command').textContent = text;
  $('command').dataset.kind = kind;
  if (!copy) return;
  const button = $(kind === 'cli' ? 'copy-cli' : 'copy-curl');
  try {
    await navigator.clipboard.writeText(text);
    button.textContent = 'Copied';
  } catch {
    // No clipboard (plain http on another host): select the text for Ctrl+C.
    getSelection().selectAllChildren($('command'));
    button.textContent = 'Press Ctrl+C';
  }
  setTimeout(() => { button.textContent = kind === 'cli' ? 'Copy as CLI' : 'Copy as curl'; }, 1500);
}

// ---------------------------------------------------------------- wiring
async function main() {
  viewer = new Viewer($('canvas'));
  const drop = $('drop');
  $('file').addEventListener('change', () => {
    const file = $('file').files[0];
    $('file').value = '';  // choosing the same file again (edited, or after a cancel) runs it again
    chooseFile(file);
  });
  for (const type of ['dragenter', 'dragover']) {
    document.addEventListener(type, (e) => { e.preventDefault(); drop.classList.add('over'); });
  }
  for (const type of ['dragleave', 'drop']) document.addEventListener(type, () => drop.classList.remove('over'));
  document.addEventListener('drop', (e) => { e.preventDefault(); chooseFile(e.dataTransfer.files[0]); });
  $('params').addEventListener('submit', (e) => { e.preventDefault(); run(); });
  $('cancel').addEventListener('click', cancel);
  $('reset').addEventListener('click', () => form.reset());
  $('download').addEventListener('click', download);
  $('copy-curl').addEventListener('click', () => showCommand('curl', true));
  $('copy-cli').addEventListener('click', () => showCommand('cli', true));
  $('reset-view').addEventListener('click', () => viewer.frame());
  for (const input of document.querySelectorAll('input[name=layout]')) {
    input.addEventListener('change', () => {
      const swipe = input.value === 'swipe';
      $('viewer').dataset.layout = input.value;
      $('split-line').hidden = $('split-control').hidden = !swipe;
      viewer.setLayout(input.value);
    });
  }
  for (const input of document.querySelectorAll('input[name=colour]')) {
    input.addEventListener('change', () => viewer.setHeatVisible(input.value === 'heat'));
  }
  $('split').addEventListener('input', () => {
    $('split-line').style.left = `${100 * $('split').value}%`;
    viewer.setSplit(Number($('split').value));
  });

  try {
    const params = await getJson('/v1/params');
    const schema = await getJson('/v1/params/schema');
    form = new ParamForm(params, schema, { main: $('fields-main'), more: $('fields-more'), output: $('fields-output') });
    document.body.dataset.form = 'ready';
  } catch (e) {
    showError(problemOf(e));
  }
}

main();
