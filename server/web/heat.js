// The displacement heat map's state and its legend: how far each result vertex moved, as a
// distance (0 to the scale's end) or signed along the result's normal (in: negative, out:
// positive; the scale runs from -end to +end), or, once a reference is given, each result
// vertex's deviation from the reference (from the server's comparison, POST /v1/compare), with the scale's end set by the user (in mean
// input edge lengths) or at the 99th percentile. The viewer colours the lit surface; the legend
// draws the same scale, its labels and a histogram of the vertices over it.
import { count, num } from './format.js';
import { scaleColour } from './viewer.js';

const $ = (id) => document.getElementById(id);
const BINS = 32;

// The value at fraction f of the sorted values.
function quantile(sorted, f) { return sorted.length ? sorted[Math.min(sorted.length - 1, Math.floor(f * sorted.length))] : 0; }

export class HeatMap {
  constructor(viewer) {
    this.viewer = viewer;
    this.data = null;  // {moved, signed, exact, edge}
    this.mode = 'distance';
    this.end = 0;      // the scale's end, model units
    for (const input of document.querySelectorAll('input[name=heat-mode]')) {
      input.addEventListener('change', () => { this.mode = input.value; this.apply(); });
    }
    $('heat-range').addEventListener('change', () => this.setEndText($('heat-range').value));
    $('heat-range').addEventListener('keydown', (e) => { if (e.key === 'Enter') { e.preventDefault(); this.setEndText($('heat-range').value); } });
    $('heat-auto').addEventListener('click', () => { this.end = this.percentileEnd(); this.apply(); });
  }

  // data: {moved, signed, exact, edge} from meshes.displacements, or null (nothing to show).
  set(data) {
    this.data = data;
    this.setReference(null);
    $('legend').hidden = !data;
    if (!data) return;
    const sorted = Float32Array.from(data.moved).sort();
    const absSigned = Float32Array.from(data.signed, Math.abs).sort();
    this.stats = {
      p99: quantile(sorted, 0.99) || sorted[sorted.length - 1] || 0, max: sorted[sorted.length - 1] ?? 0,
      p99Signed: quantile(absSigned, 0.99) || absSigned[absSigned.length - 1] || 0,
      mean: data.moved.reduce((a, b) => a + b, 0) / (data.moved.length || 1),
    };
    this.end = this.percentileEnd();
    this.apply();
  }

  // reference: {deviation (per result vertex, model units), signed, edge (the reference's mean
  // edge length)}, or null; the mode "Reference" is offered while one is set.
  setReference(reference) {
    this.reference = reference;
    const input = document.querySelector('input[name=heat-mode][value=reference]');
    input.closest('label').hidden = !reference;
    if (reference) {
      const abs = Float32Array.from(reference.deviation, Math.abs).sort();
      reference.p99 = quantile(abs, 0.99) || abs[abs.length - 1] || 0;
      input.checked = true;
      this.mode = 'reference';
      this.end = this.percentileEnd();
      this.apply();
    } else if (this.mode === 'reference') {
      document.querySelector('input[name=heat-mode][value=distance]').checked = true;
      this.mode = 'distance';
      if (this.data) { this.end = this.percentileEnd(); this.apply(); }
    }
  }

  percentileEnd() { return this.mode === 'reference' ? this.reference.p99 : this.mode === 'signed' ? this.stats.p99Signed : this.stats.p99; }
  get edge() { return this.mode === 'reference' ? this.reference.edge : this.data?.edge ?? 0; }
  get mean() { return this.stats?.mean ?? 0; }
  get max() { return this.stats?.max ?? 0; }

  // The user's end of the scale, in edge lengths: a number above 0, else said beside the field.
  setEndText(text) {
    const x = Number(String(text).trim());
    const field = $('heat-range');
    const ok = String(text).trim() !== '' && Number.isFinite(x) && x > 0;
    field.setAttribute('aria-invalid', ok ? 'false' : 'true');
    $('heat-range-error').hidden = ok;
    $('heat-range-error').textContent = ok ? '' : 'Enter a distance above 0, in edge lengths.';
    if (!ok || !this.data) return;
    this.end = x * (this.edge > 0 ? this.edge : 1);
    this.apply();
  }

  // Colours, legend and histogram for the current mode and end.
  apply() {
    if (!this.data) return;
    const ref = this.mode === 'reference';
    const signed = ref ? this.reference.signed : this.mode === 'signed';
    const end = this.end > 0 ? this.end : 0;
    const values = ref ? this.reference.deviation : signed ? this.data.signed : this.data.moved;
    const t = new Float32Array(values.length);
    for (let i = 0; i < values.length; ++i) t[i] = end > 0 ? (signed ? 0.5 + values[i] / (2 * end) : values[i] / end) : signed ? 0.5 : 0;
    this.viewer.setHeat(t, signed);
    const edges = this.edge > 0 ? end / this.edge : 0;
    $('heat-range').value = num(edges);
    $('heat-range').setAttribute('aria-invalid', 'false');
    $('heat-range-error').hidden = true;
    const bar = $('legend-bar'), ctx = bar.getContext('2d');
    for (let x = 0; x < bar.width; ++x) {
      const [r, g, b] = scaleColour(x / (bar.width - 1), signed);
      ctx.fillStyle = `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
      ctx.fillRect(x, 0, 1, bar.height);
    }
    $('legend-title').textContent = ref ? `Deviation from the reference${signed ? ', in (−) or out (+)' : ''}`
      : signed ? 'How far each vertex moved in (−) or out (+)' : 'How far each vertex moved';
    $('legend-min').textContent = signed ? `−${num(edges)} · in` : '0';
    $('legend-mid').textContent = signed ? '0' : '';
    $('legend-max').textContent = `${signed ? '+' : ''}${num(edges)} edge lengths · ${num(end)} model units${signed ? ' · out' : ''}`;
    $('legend-max').dataset.edgeLengths = String(edges);
    $('legend-max').dataset.modelUnits = String(end);
    $('legend').dataset.mode = this.mode;
    const how = ref ? (signed ? 'Each result vertex against the same reference vertex, along the reference\'s normal (computed by the server)'
                              : 'Each result vertex\'s distance to the closest point of the reference surface (computed by the server)')
      : this.data.exact ? 'Each result vertex against the same input vertex (the file keeps the input\'s vertex order)'
      : 'Each result vertex against the nearest input vertex (the result\'s vertices were reordered)';
    $('legend-note').textContent = `${how}${signed && !ref ? ', along the result\'s normal' : ''}; mean ${ref ? 'reference' : 'input'} edge length ${num(this.edge)} model units. ` +
      `${Math.abs(end - this.percentileEnd()) < 1e-12 * (1 + end) ? 'The scale ends at the 99th percentile' : 'The scale ends where you set it'}; ` +
      'values beyond it take its end colour. Click the result to read one vertex.';
    this.drawHistogram(values, end, signed);
  }

  // Vertices over the legend's range in 32 bins (the outer ones also hold what lies beyond),
  // each bar in its bin's colour, heights relative to the fullest bin.
  drawHistogram(values, end, signed) {
    const canvas = $('histogram'), ctx = canvas.getContext('2d');
    const bins = new Uint32Array(BINS);
    for (const d of values) {
      const f = end > 0 ? (signed ? 0.5 + d / (2 * end) : d / end) : signed ? 0.5 : 0;
      bins[Math.max(0, Math.min(BINS - 1, Math.floor(f * BINS)))]++;
    }
    const most = Math.max(1, ...bins);
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    const w = canvas.width / BINS;
    bins.forEach((n, i) => {
      const [r, g, b] = scaleColour((i + 0.5) / BINS, signed);
      ctx.fillStyle = `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
      const h = n === 0 ? 0 : Math.max(1, Math.round((n / most) * canvas.height));
      ctx.fillRect(i * w + 0.5, canvas.height - h, w - 1, h);
    });
    canvas.dataset.bins = Array.from(bins).join(',');
    canvas.setAttribute('aria-label', `Histogram of the distances moved: ${count(values.length)} vertices in ${BINS} bins from ${signed ? `−${num(end)}` : 0} to ${num(end)} model units`);
  }

  // The text of one picked vertex.
  describe(index) {
    if (!this.data || index >= this.data.moved.length) return null;
    const d = this.data.moved[index], s = this.data.signed[index];
    const e = this.data.edge > 0 ? this.data.edge : 1;
    return { moved: d, text: `Vertex ${count(index)} moved ${num(d / e)} edge lengths (${num(d)} model units), ${s < 0 ? 'in' : 'out'} ${num(Math.abs(s) / e)} along the normal` };
  }
}
