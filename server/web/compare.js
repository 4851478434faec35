// Strengths side by side: the current file run with Auto, Light and Strong (each a job of its
// own, sent together; the server's queue runs them), each row with its state, the server's run
// time and how far it moved the surface (mean and 99th percentile, in mean input edge lengths,
// measured as the heat map is); "Show" makes a row the page's result (view, heat map, report,
// Download), "Download" saves it directly.
import { jobResult } from './api.js';
import { bytesText, num, percent, saveBlob, seconds } from './format.js';
import { STRENGTHS } from './form.js';
import { followJob, sendJob } from './jobs.js';
import { displacements, loadMesh } from './meshes.js';

const KEYS = ['auto', 'light', 'strong'];
const $ = (id) => document.getElementById(id);
const el = (tag, props = {}, ...children) => {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
};

export class StrengthComparison {
  // page: {file(), before(), paramsText(key), onPick(entry), onRetry(what), onError(problem)}.
  constructor(page) {
    this.page = page;
    this.abort = null;
    this.entries = [];
    $('compare-run').addEventListener('click', () => this.run());
  }

  clear() {
    this.abort?.abort();
    this.abort = null;
    this.entries = [];
    $('compare-rows').replaceChildren();
    $('compare').dataset.state = 'idle';
    $('compare-run').disabled = false;
  }

  async run() {
    const file = this.page.file();
    if (!file) return;
    this.clear();
    const abort = this.abort = new AbortController();
    $('compare').dataset.state = 'running';
    $('compare-run').disabled = true;
    this.entries = KEYS.map((key) => ({ key, label: STRENGTHS[key].label, paramsText: this.page.paramsText(key), name: file.name }));
    $('compare-rows').replaceChildren(...this.entries.map((e) => this.row(e)));
    await Promise.all(this.entries.map((e) => this.runOne(e, file, abort).catch((err) => {
      if (err?.name === 'AbortError') return;
      e.error = err?.problem?.title ?? 'It failed';
      this.update(e, `Failed: ${e.error}`);
    })));
    if (this.abort !== abort) return;
    $('compare').dataset.state = 'done';
    $('compare-run').disabled = false;
  }

  async runOne(e, file, abort) {
    this.update(e, 'Sending…');
    let job = await sendJob(file, e.paramsText, abort.signal, { onRetry: this.page.onRetry('to send a strength') });
    job = await followJob(job, abort.signal, {
      onProgress: (j) => this.update(e, j.state === 'queued' ? 'Waiting for a worker' : `Running · ${percent(j.progress.fraction ?? 0)}`),
      onRetry: this.page.onRetry('to follow a strength'),
    });
    if (job.state !== 'succeeded') throw Object.assign(new Error(job.state), { problem: job.error ?? { title: `The job ${job.state}` } });
    this.update(e, 'Fetching the result…');
    e.job = job;
    e.bytes = await jobResult(job.id, { signal: abort.signal });
    e.resultName = `${file.name.replace(/\.[^.]*$/, '')}-${e.key}.${job.result.format}`;
    const before = this.page.before();
    if (before) {
      const after = (await loadMesh(new Blob([e.bytes]), job.result.format, { info: false })).geometry;
      const { moved, edge } = await displacements(before, after);
      const sorted = Float32Array.from(moved).sort();
      e.mean = moved.reduce((a, b) => a + b, 0) / (moved.length || 1) / (edge || 1);
      e.p99 = sorted[Math.min(sorted.length - 1, Math.floor(0.99 * sorted.length))] / (edge || 1);
    }
    this.update(e, 'Done');
  }

  row(e) {
    e.cell = el('td');
    e.show = el('button', { type: 'button', textContent: 'Show', disabled: true });
    e.save = el('button', { type: 'button', textContent: 'Download', disabled: true });
    e.show.setAttribute('aria-label', `Show the ${e.label} result`);
    e.save.setAttribute('aria-label', `Download the ${e.label} result`);
    e.show.addEventListener('click', () => this.page.onPick(e));
    e.save.addEventListener('click', () => saveBlob(new Blob([e.bytes], { type: e.job.result.media_type }), e.resultName));
    const tr = el('tr', {}, el('th', { scope: 'row', textContent: e.label }), e.cell, el('td', { className: 'compare-actions' }, e.show, e.save));
    tr.dataset.strength = e.key;
    return tr;
  }

  // The row's text: its state while it runs, then the server's run time, how far the surface
  // moved and the file's size.
  update(e, text) {
    const done = Boolean(e.bytes);
    e.cell.textContent = !done ? text
      : `${seconds(e.job.timings_s.run)} on the server · moved ${e.mean === undefined ? '(not drawn)' : `mean ${num(e.mean)}, 99% ${num(e.p99)} edge lengths`} · ${bytesText(e.job.result.bytes)}`;
    e.cell.dataset.mean = done && e.mean !== undefined ? String(e.mean) : '';
    e.cell.dataset.runS = done ? String(e.job.timings_s.run) : '';
    e.show.disabled = e.save.disabled = !done;
  }
}
