// The page: choose or drop a mesh, it is denoised as an asynchronous job (POST /v1/jobs with
// upload progress, long polls for the stage, DELETE to cancel, a keepalive DELETE when the page
// goes away), and the input and the result are shown in 3D with the job's report.
//
// document.body.dataset.state is what the page is doing (styling, and what its tests wait for):
//   empty      nothing chosen yet
//   invalid    a field is wrong: named in the action bar, marked, focused; nothing was sent
//   loading    the file is being sent (upload progress), or the page waits to send it again
//              (the server could not be reached: it retries with backoff)
//   running    the job is queued or running, or its result is being fetched and drawn
//   done | failed | cancelled
// Everything shown belongs to the current file and parameters: a new file clears the input's
// view and information and the result; a new run clears the result once the server accepted
// it (a run that cannot be sent keeps the previous result); a changed parameter marks a shown
// result as out of date (#stale).
import { ApiError, cancelJob, cancelOnLeave, getJson, jobResult, onTokenNeeded, token } from './api.js';
import { definitions, fileContents, outputPanel, summaryLine, timings, whatRan } from './describe.js';
import { StrengthComparison } from './compare.js';
import { bytesText, count, num, percent, saveBlob, seconds } from './format.js';
import { ParamForm } from './form.js';
import { HeatMap } from './heat.js';
import { followJob, sendJob } from './jobs.js';
import { ReferenceComparison } from './reference.js';
import { displacements, formatOf, loadMesh } from './meshes.js';
import { Viewer } from './viewer.js';

const $ = (id) => document.getElementById(id);

const state = {
  file: null, before: null, beforeLoad: null, job: null, result: null, resultName: '', abort: null,
  started: 0, cancelling: false, moved: null, legend: null,
};
let form, viewer, heat, compare, reference;

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

const elapsed = () => seconds((performance.now() - state.started) / 1000);

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
  viewer.setMesh('after', null);
  heat.set(null);
  reference?.clear();
  $('reference').hidden = true;
  $('results').hidden = true;
  $('done-bar').hidden = true;
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
  state.beforeProblem = null;
  compare?.clear();
  $('compare').hidden = true;
}

// The invalid-field error names the first field still wrong (or goes when none is).
function showInvalid(invalid) {
  showError({ title: `Check ${invalid.field}`, detail: `${invalid.message}. Fix it, then press Denoise.` });
}

// A parameter changed: a result on screen no longer shows what Denoise would make.
function paramsChanged() {
  if (!state.file) return;
  $('run').disabled = document.body.dataset.state === 'loading' || document.body.dataset.state === 'running';
  if (document.body.dataset.state === 'invalid') {
    const still = form.firstInvalid({ focus: false });
    if (still) {
      showInvalid(still);
    } else {
      showError(null);
      setState(state.result ? 'done' : 'empty');
      setStage('Ready: press Denoise.', 0);
    }
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
  if (file.size === 0) {
    // Nothing to send: said plainly, before any request.
    state.file = null;
    $('run').disabled = true;
    setState('failed');
    setStage('Not sent: the file is empty.', 0);
    showError({ title: `${file.name} is empty`, detail: 'It has 0 bytes, so there is no mesh in it. If it is still being written or copied, wait and choose it again; otherwise choose another file.' });
    $('viewer-empty').textContent = `${file.name} is empty: nothing to show.`;
    return;
  }
  $('viewer-empty').textContent = `Reading ${file.name} in the browser…`;
  // Read and drawn in the worker while the upload goes: neither waits for the other.
  state.beforeInfo = null;
  const load = state.beforeLoad = (async () => {
    const format = await formatOf(file.name, file);
    try {
      const { geometry, info } = await loadMesh(file, format);
      if (state.beforeLoad !== load) return;  // another file was chosen meanwhile
      state.before = geometry;
      state.beforeInfo = info;
      viewer.setMesh('before', geometry);
      viewer.frame();
      $('viewer-empty').hidden = true;
      showMeshInfo(info, file.name);
    } catch (e) {
      if (state.beforeLoad !== load) return;
      // The server is the judge of what it reads: it runs anyway, and the result is shown alone;
      // if the server refuses the file too, its reason is in the action bar.
      state.beforeProblem = e.message;
      $('viewer-empty').hidden = false;
      $('viewer-empty').textContent = `The browser could not draw ${file.name}: ${e.message}.`;
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

// The server cannot be reached: said in the action bar with the next try (decision 66).
function sayRetry(what) {
  return (attempt, wait) => {
    const kept = state.result ? ' The previous result stays on screen.' : '';
    showError({ title: 'The server cannot be reached', detail: `The page tries ${what} again in ${Math.round(wait / 1000)} s (try ${attempt + 2}), and keeps trying until it answers.${kept} Cancel stops it.` });
    setStage(`The server cannot be reached · trying again in ${Math.round(wait / 1000)} s`, undefined);
  };
}

// The job's stage in the action bar.
function showJobStage(job) {
  if (state.cancelling) return;
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

async function run() {
  if (!state.file || !form) return;  // no form: the page could not start (said in the action bar)
  const invalid = form.firstInvalid({ focus: false });
  if (invalid) {
    stopJob();
    setState('invalid');
    setStage('Not sent: a parameter needs fixing.', 0);
    showInvalid(invalid);
    form.focus(invalid.field);  // after the error box: the bar has its final height
    $('run').disabled = false;
    $('cancel').disabled = true;
    return;
  }
  showError(null);
  stopJob();
  const abort = state.abort = new AbortController();
  const paramsText = form.paramsText();
  const strength = form.strength.value;
  state.job = null;
  state.cancelling = false;
  state.started = performance.now();
  setState('loading');
  $('run').disabled = true;
  $('cancel').disabled = false;
  const file = state.file;
  try {
    setStage(`Sending ${file.name} · 0 %`, 0);
    let job = await sendJob(file, paramsText, abort.signal, {
      onUpload: (sent, total) => setStage(`Sending ${file.name} · ${percent(sent / (total || 1))} of ${bytesText(total)}`, sent / (total || 1)),
      onRetry: sayRetry('to send the file'), onSent: () => showError(null),
    });
    // Accepted: the previous result no longer belongs to what runs.
    clearResult();
    state.job = { id: job.id, paramsText, name: file.name, running: true, strength };
    setState('running');
    job = await followJob(job, abort.signal, { onProgress: showJobStage, onRetry: sayRetry('to follow the job'), onBack: () => showError(null) });
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
    await showResult(job, bytes, abort);
  } catch (e) {
    if (e?.name === 'AbortError') {
      if (state.abort === abort || state.cancelling) {  // Cancel pressed before the job existed
        setState(state.result ? 'done' : 'cancelled');
        setStage(state.result ? 'Not sent: cancelled. The previous result is shown.' : 'Cancelled.', state.result ? 1 : 0);
        showError(null);
      }
      return;
    }
    if (state.abort !== abort) return;  // another run took over
    if (state.job) state.job.running = false;
    await state.beforeLoad;  // the browser's own reading first, so that the view says what it found
    if (state.abort !== abort) return;
    setState('failed');
    setStage(state.job ? 'The job could not be followed.' : 'Not accepted.', 0);
    showError(problemOf(e));
    if (!state.result && state.beforeProblem) {
      $('viewer-empty').textContent = `Nothing to show: the browser could not draw ${file.name} (${state.beforeProblem}) and the server did not accept it.`;
    }
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
async function showResult(job, bytes, abort, name = null) {
  const result = job.result;
  const drawStart = performance.now();
  setStage('Drawing the result · reading it', 0.1);
  state.result = new Blob([bytes], { type: result.media_type });
  state.resultName = name ?? `${state.file.name.replace(/\.[^.]*$/, '')}-denoised.${result.format}`;
  let after = null;
  try {
    after = (await loadMesh(state.result, result.format, { info: false })).geometry;
  } catch (e) {
    showError({ title: 'The result cannot be drawn', detail: `The browser could not draw it: ${e.message}. Download it to see it elsewhere.` });
  }
  const parsed = performance.now();
  await state.beforeLoad;  // the input drawn (or given up) first: the heat map needs it
  if (state.abort !== abort) return;  // another run took over
  // The displacement (distance moved, in mean edge lengths of the input, the unit of the
  // method's noise measures, and in model units), then the mesh and its colours in one frame.
  let moved = null;
  if (state.before && after) {
    setStage('Drawing the result · measuring the displacement', 0.5);
    moved = await displacements(state.before, after);
    if (state.abort !== abort) return;
  }
  const measured = performance.now();
  setStage('Drawing the result · drawing', 0.8);
  await viewer.batch(() => {
    viewer.setMesh('after', after);
    if (!state.before) viewer.frame();
    heat.set(moved);
  });
  $('viewer-empty').hidden = Boolean(state.before || after);
  if (state.abort !== abort) return;
  const drawn = performance.now();
  // How long each part of the drawing took (ms), for the bench script and the summary.
  Object.assign(document.body.dataset, { drawMs: String(drawn - drawStart), drawParseMs: String(parsed - drawStart),
                                         drawMeasureMs: String(measured - parsed), drawRenderMs: String(drawn - measured) });
  state.drawMs = performance.now() - drawStart;
  const wall = (performance.now() - state.started) / 1000;
  $('summary').replaceChildren(...definitions([
    ['Time', `${seconds(wall)} in all · queue ${seconds(job.timings_s.queue_wait)} · run ${seconds(job.timings_s.run)} · drawing ${seconds(state.drawMs / 1000)}`],
    ['Input', `${state.file.name} · ${bytesText(job.input_bytes)}`],
    ['Mesh', `${count(result.vertices)} vertices · ${count(result.faces)} faces`],
    ...(heat.data ? [['Moved', `mean ${num(heat.mean / heat.edge)} · max ${num(heat.max / heat.edge)} edge lengths`]] : []),
  ]));
  $('reports').replaceChildren(whatRan(result.reports, JSON.parse(state.job.paramsText), state.job.strength));
  $('timings').replaceChildren(...timings(result.timings_ms, STAGE_NAMES));
  const inputBytes = await state.file.arrayBuffer().catch(() => new ArrayBuffer(0));
  if (state.abort !== abort) return;
  $('output-panel').replaceChildren(...outputPanel(
    { format: await formatOf(state.file.name, state.file), contents: fileContents(inputBytes, await formatOf(state.file.name, state.file)), info: state.beforeInfo },
    { contents: fileContents(bytes, result.format) }, job));
  $('download').textContent = `Download ${state.resultName}`;
  $('result-line').textContent = summaryLine(result, heat, wall);
  $('done-bar').hidden = false;
  showCommand('curl');
  $('results').hidden = false;
  $('compare').hidden = false;
  reference.clear();
  $('reference').hidden = false;
  setStage(`Done in ${seconds(wall)}.`, 1);
  setState('done');
  paramsChanged();
}

// A strength of the side-by-side runs becomes the page's result (view, heat map, report,
// Download); the form's strength follows, so that Denoise would make it again.
async function pickStrength(entry) {
  stopJob();
  showError(null);
  form.setStrength(entry.key);
  state.job = { id: entry.job.id, paramsText: entry.paramsText, name: entry.name, running: false, strength: entry.key };
  state.started = performance.now();
  setState('running');
  await showResult(entry.job, entry.bytes, state.abort, entry.resultName);
  setStage(`Showing ${entry.label}.`, 1);
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
  const d = heat.describe(hit.index);
  const position = hit.position.toArray().map(num).join(', ');
  info.textContent = d ? d.text : `Vertex ${count(hit.index)} at (${position})`;
  info.dataset.vertex = String(hit.index);
  info.dataset.moved = d ? String(d.moved) : '';
  info.hidden = false;
}

// ---------------------------------------------------------------- download, commands
function download() {
  if (state.result) saveBlob(state.result, state.resultName);
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
  heat = new HeatMap(viewer);
  reference = new ReferenceComparison({
    input: () => state.file, heat,
    result: () => (state.result && heat.data ? { blob: state.result, name: state.resultName, vertices: heat.data.moved.length } : null),
  });
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
    compare = new StrengthComparison({
      file: () => state.file, before: () => state.before, paramsText: (key) => form.strengthParamsText(key),
      onPick: pickStrength, onRetry: sayRetry,
    });
    document.body.dataset.form = 'ready';
  } catch (e) {
    setState('failed');
    setStage('The page could not start.', 0);
    showError(problemOf(e));
  }
}

main();
