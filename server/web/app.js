// The page: choose or drop a mesh, it is denoised as an asynchronous job (POST /v1/jobs with
// upload progress, long polls for the stage, DELETE to cancel, a keepalive DELETE when the page
// goes away), and the input and the result are shown in 3D with the job's report.
//
// document.body.dataset.state is what the page is doing (styling, and what its tests wait for):
//   empty      nothing chosen yet
//   invalid    a field is wrong: named in the action bar, marked, focused; nothing was sent
//   loading    the file is being sent (upload progress)
//   running    the job is queued or running, or its result is being fetched and drawn
//   done | failed | cancelled
// Everything shown belongs to the current file and parameters: a new file clears the input's
// view and information and the result; a new run clears the result; a changed parameter marks
// a shown result as out of date (#stale).
import { ApiError, cancelJob, cancelOnLeave, getJson, jobResult, onTokenNeeded, pollJob, submitJob, token } from './api.js';
import { ParamForm } from './form.js';
import { displacements, formatName, formatOf, loadMesh } from './meshes.js';
import { scaleColour, Viewer } from './viewer.js';

const $ = (id) => document.getElementById(id);
const POLL_S = 0.5;  // long-poll window: progress is redrawn at least this often

const state = {
  file: null, before: null, beforeLoad: null, job: null, result: null, resultName: '', abort: null,
  started: 0, cancelling: false, moved: null, legend: null,
};
let form, viewer;

function setState(name) { document.body.dataset.state = name; }

// Errors go to the action bar (always in view). A problem naming a field marks it too.
function showError(problem) {
  $('error').hidden = !problem;
  if (!problem) return;
  $('error-title').textContent = problem.title ?? 'Something went wrong';
  $('error-detail').textContent = problem.detail ?? '';
  form?.showProblemField(problem);
}

function problemOf(e) {
  if (e instanceof ApiError) return e.problem;
  return { title: 'Something went wrong in the page', detail: 'Reload the page and try again.' };
}

// fraction undefined: an indeterminate bar (work of unknown length).
function setStage(text, fraction) {
  $('stage').textContent = text;
  if (fraction === undefined) $('progress').removeAttribute('value');
  else $('progress').value = fraction;
}

const bytesText = (n) => n >= 1 << 20 ? `${(n / (1 << 20)).toFixed(1)} MiB` : n >= 1024 ? `${(n / 1024).toFixed(0)} KiB` : `${n} B`;
const seconds = (s) => `${s.toFixed(s < 10 ? 1 : 0)} s`;
const num = (x) => (Math.abs(x) >= 1000 || Math.abs(x) < 0.01) && x !== 0 ? x.toExponential(2) : String(+x.toPrecision(3));
const count = (n) => n.toLocaleString('en');
const elapsed = () => seconds((performance.now() - state.started) / 1000);
const percent = (f) => `${Math.floor(100 * f)} %`;

// The server's stage identifiers, as people say them.
const STAGE_NAMES = {
  queued: 'Waiting for a worker', decode: 'Reading the mesh on the server', select_parameters: 'Choosing parameters',
  initial_prefilter: 'Pre-filtering vertices', region_prefilter: 'Region pre-filter', anisotropic_prefilter: 'Anisotropic pre-filter',
  normal_filter: 'Filtering normals', vertex_update: 'Moving vertices', encode: 'Writing the result', done: 'Writing the result',
  setup: 'Setting up', measure: 'Measuring the surface',
};
const stageName = (id) => STAGE_NAMES[id] ?? (id ? id.replaceAll('_', ' ') : 'Working');

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

// ---------------------------------------------------------------- what is shown
function clearResult() {
  state.result = null;
  state.moved = null;
  state.legend = null;
  viewer.setMesh('after', null);
  $('results').hidden = true;
  $('legend').hidden = true;
  $('stale').hidden = true;
  $('pick-info').hidden = true;
  $('results').classList.remove('out-of-date');
  $('legend').classList.remove('out-of-date');
}

function clearInput() {
  state.before = null;
  viewer.setMesh('before', null);
  $('mesh-info').hidden = true;
  $('viewer-empty').hidden = false;
  $('viewer-empty').textContent = 'The noisy input and the denoised result appear here, side by side, with one camera.';
}

// A parameter changed: a result on screen no longer shows what Denoise would make.
function paramsChanged() {
  if (!state.file) return;
  $('run').disabled = document.body.dataset.state === 'loading' || document.body.dataset.state === 'running';
  if (document.body.dataset.state === 'invalid' && !form.anyInvalid()) {
    showError(null);
    setState(state.result ? 'done' : 'empty');
    setStage('Ready: press Denoise.', 0);
  }
  if (state.result && state.job && form.paramsText() !== state.job.paramsText) {
    $('stale').hidden = false;
    $('results').classList.add('out-of-date');
    $('legend').classList.add('out-of-date');
  } else {
    $('stale').hidden = true;
    $('results').classList.remove('out-of-date');
    $('legend').classList.remove('out-of-date');
  }
}

function showMeshInfo(info, name) {
  const size = info.max.map((m, k) => m - info.min[k]);
  $('mesh-info').textContent = `${name}: ${count(info.vertices)} vertices · ${count(info.faces)} faces · ` +
    `size ${size.map(num).join(' × ')} · ${info.open_edges === 0 ? 'closed (no open edges)' : `${count(info.open_edges)} open edges`}` +
    (info.non_manifold_edges ? ` · ${count(info.non_manifold_edges)} non-manifold edges` : '');
  $('mesh-info').hidden = false;
}

// ---------------------------------------------------------------- input
async function chooseFile(file) {
  if (!file) return;
  // A job still running for the previous file is not wanted any more (run() cancels it too,
  // but the file may never run: a field may be wrong).
  stopJob();
  showError(null);
  clearResult();
  clearInput();
  state.file = file;
  $('file-name').textContent = `${file.name} · ${bytesText(file.size)}`;
  $('viewer-empty').textContent = `Reading ${file.name} in the browser…`;
  // Read and drawn in the worker while the upload goes: neither waits for the other.
  const load = state.beforeLoad = (async () => {
    const format = await formatOf(file.name, file);
    try {
      const { geometry, info } = await loadMesh(file, format);
      if (state.beforeLoad !== load) return;  // another file was chosen meanwhile
      state.before = geometry;
      viewer.setMesh('before', geometry);
      viewer.frame();
      $('viewer-empty').hidden = true;
      showMeshInfo(info, file.name);
    } catch (e) {
      if (state.beforeLoad !== load) return;
      // The server is the judge of what it reads: it runs anyway, the result is shown alone.
      $('viewer-empty').hidden = false;
      $('viewer-empty').textContent = `The browser could not draw ${file.name}: ${e.message}. The server reads files on its own.`;
    }
  })();
  $('run').disabled = false;
  await run();
}

// ---------------------------------------------------------------- the job
// Drops the current run: the upload or poll is aborted, a job on the server is cancelled.
function stopJob() {
  state.abort?.abort();
  state.abort = null;
  if (state.job?.running) {
    state.job.running = false;
    cancelJob(state.job.id).catch(() => {});
  }
}

async function run() {
  if (!state.file || !form) return;  // no form: the page could not start (said in the action bar)
  const invalid = form.firstInvalid();
  if (invalid) {
    stopJob();
    setState('invalid');
    setStage('Not sent: a parameter needs fixing.', 0);
    showError({ title: `Check ${invalid.field}`, detail: `${invalid.message}. Fix it, then press Denoise.` });
    $('run').disabled = false;
    $('cancel').disabled = true;
    return;
  }
  showError(null);
  stopJob();
  const abort = state.abort = new AbortController();
  const paramsText = form.paramsText();
  state.job = null;
  state.cancelling = false;
  clearResult();
  state.started = performance.now();
  setState('loading');
  $('run').disabled = true;
  $('cancel').disabled = false;
  const file = state.file;
  setStage(`Sending ${file.name} · 0 %`, 0);
  try {
    let job = await submitJob(file, paramsText, {
      signal: abort.signal,
      onUpload: (sent, total) => setStage(`Sending ${file.name} · ${percent(sent / (total || 1))} of ${bytesText(total)}`, sent / (total || 1)),
    });
    state.job = { id: job.id, paramsText, name: file.name, running: true };
    setState('running');
    while (job.state === 'queued' || job.state === 'running') {
      if (!state.cancelling) {
        const p = job.progress;
        if (job.state === 'queued') {
          const ahead = p.jobs_ahead;
          setStage(`${stageName('queued')}${ahead === undefined ? '' : ahead === 0 ? ' · next in line' : ` · ${ahead} ${ahead === 1 ? 'job' : 'jobs'} ahead`} · ${elapsed()}`, undefined);
        } else if (p.stage === 'decode' && !(p.fraction > 0)) {
          setStage(`${stageName('decode')} · ${elapsed()}`, undefined);
        } else {
          setStage(`${stageName(p.stage)} · ${percent(p.fraction)} · ${elapsed()}`, p.fraction);
        }
      }
      job = await pollJob(job.id, POLL_S, abort.signal);
    }
    state.job.running = false;
    if (job.state === 'cancelled') {
      setState('cancelled');
      setStage(`Cancelled after ${elapsed()}.`, 0);
      return;
    }
    if (job.state !== 'succeeded') {
      setState('failed');
      setStage('The job failed.', 0);
      showError(job.error ?? { title: 'The job failed', detail: 'The server gave no reason.' });
      return;
    }
    setStage('Fetching the result · 0 %', 0);
    const bytes = await jobResult(job.id, {
      signal: abort.signal,
      onProgress: (got, total) => setStage(`Fetching the result · ${total ? `${percent(got / total)} of ${bytesText(total)}` : bytesText(got)}`, total ? got / total : undefined),
    });
    setStage('Drawing the result…', undefined);
    await showResult(job, bytes, abort);
  } catch (e) {
    if (e?.name === 'AbortError') {
      if (state.abort === abort || state.cancelling) {  // Cancel pressed before the job existed
        setState('cancelled');
        setStage('Cancelled.', 0);
      }
      return;
    }
    if (state.abort !== abort) return;  // another run took over
    if (state.job) state.job.running = false;
    setState('failed');
    setStage(state.job ? 'The job could not be followed.' : 'Not accepted.', 0);
    showError(problemOf(e));
  } finally {
    if (state.abort === abort) {
      $('run').disabled = !state.file;
      $('cancel').disabled = true;
      state.cancelling = false;
    }
  }
}

// The user's own Cancel: said as it happens, never as an error.
async function cancel() {
  state.cancelling = true;
  $('cancel').disabled = true;
  if (!state.job?.running) {
    state.abort?.abort();  // still sending (the upload is dropped) or fetching the result
    return;
  }
  setStage('Cancelling…', undefined);
  try {
    await cancelJob(state.job.id);
  } catch (e) {
    state.cancelling = false;
    showError(problemOf(e));
  }
}

// ---------------------------------------------------------------- the result
async function showResult(job, bytes, abort) {
  const result = job.result;
  state.result = new Blob([bytes], { type: result.media_type });
  state.resultName = `${state.file.name.replace(/\.[^.]*$/, '')}-denoised.${result.format}`;
  let after = null;
  try {
    after = (await loadMesh(state.result, result.format)).geometry;
  } catch (e) {
    showError({ title: 'The result cannot be drawn', detail: `The browser could not draw it: ${e.message}. Download it to see it elsewhere.` });
  }
  await state.beforeLoad;  // the input drawn (or given up) first: the heat map needs it
  if (state.abort !== abort) return;  // another run took over
  viewer.setMesh('after', after);
  if (!state.before) viewer.frame();
  $('viewer-empty').hidden = Boolean(state.before || after);

  // The heat map: distance moved, in mean edge lengths of the input (the unit of the method's
  // noise measures) and in model units. The scale ends at the 99th percentile (outliers aside).
  let legend = null;
  if (state.before && after) {
    const { moved, edge } = await displacements(state.before, after);
    if (state.abort !== abort) return;
    const sorted = Float32Array.from(moved).sort();
    const top = sorted[Math.min(sorted.length - 1, Math.floor(0.99 * sorted.length))] || sorted[sorted.length - 1] || 0;
    viewer.setHeat(Array.from(moved, (d) => (top > 0 ? d / top : 0)));
    state.moved = moved;
    legend = state.legend = { edge, top, max: sorted[sorted.length - 1] ?? 0, mean: moved.reduce((a, b) => a + b, 0) / (moved.length || 1) };
  }
  showLegend(legend, state.moved);

  const wall = (performance.now() - state.started) / 1000;
  $('summary').replaceChildren(...[
    ['Time', `${seconds(wall)} in all · queue ${seconds(job.timings_s.queue_wait)} · run ${seconds(job.timings_s.run)}`],
    ['Input', `${state.file.name} · ${bytesText(job.input_bytes)}`],
    ['Output', `${formatName(result.format)}${result.compression === 'draco' ? ' (Draco)' : result.compression === 'meshopt' ? ' (meshopt)' : ''} · ${bytesText(result.bytes)}`],
    ['Mesh', `${count(result.vertices)} vertices · ${count(result.faces)} faces`],
    ...(legend ? [['Moved', `mean ${num(legend.mean / legend.edge)} · max ${num(legend.max / legend.edge)} edge lengths`]] : []),
    ...result.notes.map((n) => ['Note', n]),
  ].flatMap(([k, v]) => [Object.assign(document.createElement('dt'), { textContent: k }), Object.assign(document.createElement('dd'), { textContent: v })]));
  showReports(result.reports, state.job.paramsText);
  showTimings(result.timings_ms);
  $('download').textContent = `Download ${state.resultName}`;
  showCommand('curl');
  $('results').hidden = false;
  setStage(`Done in ${seconds(wall)}.`, 1);
  setState('done');
  paramsChanged();
}

function showLegend(legend, moved) {
  $('legend').hidden = !legend;
  if (!legend) return;
  const bar = $('legend-bar'), ctx = bar.getContext('2d');
  for (let x = 0; x < bar.width; ++x) {
    const [r, g, b] = scaleColour(x / (bar.width - 1));
    ctx.fillStyle = `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
    ctx.fillRect(x, 0, 1, bar.height);
  }
  const edges = legend.edge > 0 ? legend.top / legend.edge : 0;
  $('legend-max').textContent = `${num(edges)} edge lengths · ${num(legend.top)} model units`;
  $('legend-min').textContent = '0';
  $('legend-max').dataset.edgeLengths = String(edges);
  $('legend-max').dataset.modelUnits = String(legend.top);
  $('legend-note').textContent = `Distance from each result vertex to the nearest input vertex; mean input edge length ${num(legend.edge)} model units. The scale ends at the 99th percentile. Click the result to read one vertex.`;
  drawHistogram(moved, legend.top);
}

// Vertices by distance moved: 32 bins over the legend's range (the last one also holds what lies
// beyond it), each bar in the colour of its bin's middle, heights relative to the fullest bin.
function drawHistogram(moved, top) {
  const canvas = $('histogram'), ctx = canvas.getContext('2d');
  const bins = new Uint32Array(32);
  for (const d of moved) bins[Math.min(31, top > 0 ? Math.floor((d / top) * 32) : 0)]++;
  const most = Math.max(1, ...bins);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const w = canvas.width / 32;
  bins.forEach((n, i) => {
    const [r, g, b] = scaleColour((i + 0.5) / 32);
    ctx.fillStyle = `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
    const h = n === 0 ? 0 : Math.max(1, Math.round((n / most) * canvas.height));
    ctx.fillRect(i * w + 0.5, canvas.height - h, w - 1, h);
  });
  canvas.dataset.bins = Array.from(bins).join(',');
  canvas.setAttribute('aria-label', `Histogram of the distances moved: ${count(moved.length)} vertices in 32 bins from 0 to ${num(top)} model units`);
}

// A click (not a drag) on the result: the nearest vertex of the face under the pointer and how
// far it moved.
function pickAt(x, y) {
  const hit = viewer.pick(x, y);
  const info = $('pick-info');
  if (!hit) {
    info.hidden = true;
    viewer.clearPick();
    return;
  }
  const d = state.moved?.[hit.index];
  const position = hit.position.toArray().map(num).join(', ');
  info.textContent = d === undefined
    ? `Vertex ${count(hit.index)} at (${position})`
    : `Vertex ${count(hit.index)} moved ${num(d / state.legend.edge)} edge lengths (${num(d)} model units)`;
  info.dataset.vertex = String(hit.index);
  info.dataset.moved = d === undefined ? '' : String(d);
  info.hidden = false;
}

function table(rows, head) {
  const t = document.createElement('table');
  if (head) t.createTHead().insertRow().append(...head.map((h) => Object.assign(document.createElement('th'), { textContent: h })));
  const body = t.createTBody();
  for (const r of rows) body.insertRow().append(...r.map((c) => Object.assign(document.createElement('td'), { textContent: c })));
  return t;
}

// Per surface: what auto measured and what ran, each parameter with where its value came from
// (given in this run's request, chosen by auto, or the default).
function showReports(reports, paramsText) {
  const given = Object.keys(JSON.parse(paramsText));
  const box = $('reports');
  box.replaceChildren();
  reports.forEach((r, i) => {
    const title = document.createElement('h3');
    title.textContent = `${reports.length > 1 ? `Surface ${i + 1} · ` : ''}mode ${r.mode}${r.region_prefilter_applied ? ` · region pre-filter on ${count(r.region_vertices)} vertices` : ''}`;
    const rows = Object.entries(r.params).filter(([k]) => k !== 'mode')
      .map(([k, v]) => [k, typeof v === 'number' ? num(v) : String(v),
                        given.includes(k) ? 'given' : r.mode === 'auto' || r.mode === 'search' ? 'auto' : 'default']);
    box.append(title, table(rows, ['Parameter', 'Ran with', 'Set by']));
    if (r.choice) {
      const c = r.choice;
      const rows = [['How', c.method === 'fallback' ? "outside the model's range: no filtering or the paper's row" : c.method === 'search' ? 'model, refined by search' : 'trained model'],
                    ['Set', c.chosen], ['Estimated noise', `${num(c.noise.sigma_edges)} edge lengths`]];
      if (c.predicted_ratio > 0) rows.push(['Predicted error', `${num(c.predicted_ratio)} x the best set's`]);
      rows.push(['Model', c.model_version]);
      for (const note of c.notes) rows.push(['Note', note]);
      box.append(table(rows, ['Parameter choice', '']));
    }
    if (r.measures) box.append(table(Object.entries(r.measures).map(([k, v]) => [k.replaceAll('_', ' '), num(v)]), ['Measured', 'Value']));
  });
}

// The stages in the order they run; any stage the server adds later follows them.
const STAGE_ORDER = ['decode', 'setup', 'measure', 'select_parameters', 'initial_prefilter', 'region_prefilter', 'anisotropic_prefilter',
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
    row.append(Object.assign(document.createElement('th'), { textContent: STAGE_NAMES[name] && name !== 'done' ? `${STAGE_NAMES[name]}` : name.replaceAll('_', ' ') }),
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
  $('reset-view').addEventListener('click', () => { viewer.frame(); viewer.clearPick(); $('pick-info').hidden = true; });
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
  for (const input of document.querySelectorAll('input[name=shading]')) {
    input.addEventListener('change', () => viewer.setSmooth(input.value === 'smooth'));
  }
  $('wireframe').addEventListener('change', () => viewer.setWireframe($('wireframe').checked));
  $('split').addEventListener('input', () => {
    $('split-line').style.left = `${100 * $('split').value}%`;
    viewer.setSplit(Number($('split').value));
  });
  // A click is a press and release within a few pixels (a drag turns the view).
  let down = null;
  $('canvas').addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
  $('canvas').addEventListener('pointerup', (e) => {
    if (down && Math.hypot(e.clientX - down.x, e.clientY - down.y) < 4) pickAt(e.clientX, e.clientY);
    down = null;
  });
  // Leaving the page (closing the tab, reloading, going elsewhere): the job it started is of no
  // use to anyone; a keepalive DELETE reaches the server after the page is gone.
  addEventListener('pagehide', () => {
    if (state.job?.running) cancelOnLeave(state.job.id);
  });

  try {
    const params = await getJson('/v1/params');
    const schema = await getJson('/v1/params/schema');
    form = new ParamForm(params, schema, {
      strength: $('strength'), strengthHelp: $('strength-help'), format: $('fields-format'),
      main: $('fields-main'), more: $('fields-more'), output: $('fields-output'),
    });
    form.onChange = paramsChanged;
    document.body.dataset.form = 'ready';
  } catch (e) {
    setState('failed');
    setStage('The page could not start.', 0);
    showError(problemOf(e));
  }
}

main();
