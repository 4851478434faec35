// The result's panels in words: what ran (per surface: the strength or the parameters, the noise
// read, why, what the user overrode; always the parameters that actually ran, from the report's
// `params`, never the model's pick when a field overrode it), the stage timings, the one-line
// summary for the action bar, and the output panel (what the file holds, sizes before and after,
// what the server checked).
import { bytesText, count, num, seconds } from './format.js';
import { STRENGTHS } from './form.js';
import { formatName } from './meshes.js';

const el = (tag, props = {}, ...children) => {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
};

// Rows of a definition list: [[term, text], ...].
export function definitions(rows) {
  return rows.flatMap(([k, v]) => [el('dt', { textContent: k }), el('dd', { textContent: v })]);
}

// The six parameters of Table 1 (and the region pre-filter) in a sentence.
export function paramsInWords(p) {
  if (!(p.n_normal > 0) && !(p.n_vertex > 0)) return 'no filtering: the surface was left as it was';
  const parts = [`${p.n_normal} normal-filter iterations keeping creases sharper than about ${num(p.sigma_gamma)}°`,
                 `${p.n_vertex} vertex iterations`,
                 `pre-smoothing weight ${num(p.alpha)}`,
                 p.n_aniso > 0 ? `${p.n_aniso} anisotropic pre-filter ${p.n_aniso === 1 ? 'pass' : 'passes'} (creases beyond ${num(p.sigma_theta)}°)` : 'no anisotropic pre-filter'];
  if (p.region_mode && p.region_mode !== 'off') parts.push(`region pre-filter ${p.region_mode}`);
  return parts.join(', ');
}

// The strength whose set equals the parameters that ran, or null.
function strengthOf(p) {
  for (const [key, { label, params }] of Object.entries(STRENGTHS)) {
    if (key === 'auto') continue;
    if (Object.entries(params).every(([k, v]) => k === 'mode' || p[k] === v)) return label;
  }
  return null;
}

// Per surface, in words. given: the parameters this run sent (parsed JSON); strength: the
// strength chosen in the form (its values were sent too).
export function whatRan(reports, given, strength) {
  // The fields the user set: those sent that are not the strength's own value.
  const preset = STRENGTHS[strength]?.params ?? {};
  const overridden = Object.keys(given).filter((k) => k !== 'mode' && k !== 'output' && !(k in preset && preset[k] === given[k]));
  const box = document.createDocumentFragment();
  reports.forEach((r, i) => {
    const rows = [];
    const p = r.params;
    const named = strengthOf(p);
    if (r.mode === 'none') {
      rows.push(['Ran', 'nothing: the mesh was converted only']);
    } else if (r.mode === 'auto' || r.mode === 'search') {
      const c = r.choice;
      const how = !c ? 'chosen for this surface'
        : c.method === 'fallback' ? `this mesh is outside what the model was trained on, so it picked ${p.n_normal > 0 ? 'the paper\'s settings' : 'no filtering'} by the error it estimated on re-noised copies`
        : c.method === 'search' ? 'the model\'s pick, then refined by a search on re-noised copies of the surface'
        : `the trained model predicted this the best of its ${count(c.sets?.length ?? 0)} settings for this surface`;
      // A field the user gave replaced the model's value: what ran is no longer the set the
      // model judged, so its prediction is not shown.
      const own = overridden.length > 0;
      rows.push(['Strength', `Auto${named ? ` (as ${named})` : ''}: ${how}${own ? `, then your ${overridden.join(', ')} in place of its ${overridden.length === 1 ? 'value' : 'values'}` : ''}`]);
      if (c) rows.push(['Noise read', `${num(c.noise.sigma_edges)} mean edge lengths (spread of the vertices off the surface)`]);
      if (!own && c?.method === 'model' && c.predicted_ratio > 0) {
        rows.push(['Expected', c.predicted_ratio <= 1.1
          ? 'about as good as the best of those settings could do'
          : `an error about ${num(c.predicted_ratio)} times what the best of those settings could do: a surface unlike most the model learned from`]);
      }
    } else {
      rows.push(['Strength', named && !overridden.length ? `${named} (fixed settings)` : named ? `${named} (fixed settings), with your own values` : 'Manual: the parameters given']);
    }
    if (r.mode !== 'none') rows.push(['Ran with', paramsInWords(p)]);
    if (overridden.length && r.mode !== 'none') {
      rows.push(['You set', `${overridden.map((k) => `${k} ${k in p ? num(p[k]) : JSON.stringify(given[k])}`).join(', ')}${r.mode === 'auto' || r.mode === 'search' ? '; auto chose the rest' : ''}`]);
    }
    if (r.region_prefilter_applied) rows.push(['Region pre-filter', `on ${count(r.region_vertices)} irregularly sampled vertices`]);
    for (const note of r.choice?.notes ?? []) rows.push(['Note', note]);
    if (reports.length > 1) box.append(el('h3', { textContent: `Surface ${i + 1}` }));
    box.append(el('dl', { className: 'summary' }, ...definitions(rows)));
  });
  // The exact values, for an engineer: the parameters as sent back to reproduce the run.
  const exact = reports.map((r) => JSON.stringify(r.params)).join('\n');
  box.append(el('details', { className: 'exact' }, el('summary', { id: 'exact-summary', textContent: 'Exact parameters (send them back to reproduce the run)' }),
                el('pre', { className: 'command', textContent: exact })));
  return box;
}

// The stages in the order they run; any stage the server adds later follows them.
const STAGE_ORDER = ['decode', 'setup', 'measure', 'select_parameters', 'initial_prefilter', 'region_prefilter', 'anisotropic_prefilter',
                     'normal_filter', 'vertex_update', 'encode'];

// Rows: name, value with its unit, a bar relative to the longest stage.
export function timings(ms, names) {
  const rank = (k) => (STAGE_ORDER.includes(k) ? STAGE_ORDER.indexOf(k) : STAGE_ORDER.length);
  const stages = Object.entries(ms).filter(([k]) => k !== 'denoise').sort(([a], [b]) => rank(a) - rank(b));
  const longest = Math.max(1e-9, ...stages.map(([, v]) => v));
  return stages.map(([name, value]) => {
    const bar = el('span', { className: 'bar' });
    bar.style.width = `${(100 * value / longest).toFixed(1)}%`;
    const row = el('li', {}, el('span', { className: 'timing-name', textContent: names[name] && name !== 'done' ? names[name] : name.replaceAll('_', ' ') }),
                   el('span', { className: 'timing-bar' }, bar),
                   el('span', { className: 'timing-value', textContent: value >= 1000 ? seconds(value / 1000) : `${value.toFixed(value < 10 ? 1 : 0)} ms` }));
    row.dataset.stage = name;
    return row;
  });
}

// The action bar's one line: what came back and how far the surface moved.
export function summaryLine(result, heat, wallS) {
  const moved = heat?.data ? ` · moved ${num(heat.mean / (heat.edge || 1))} edge lengths on average` : '';
  return `${count(result.faces)} faces · ${formatName(result.format)} ${bytesText(result.bytes)}${moved} · ${seconds(wallS)}`;
}

// ---------------------------------------------------------------- the output panel
// What a file holds, read from its bytes (headers only): {meshes, attributes, compression, kind}.
export function fileContents(bytes, format) {
  const u8 = new Uint8Array(bytes);
  const text = (a, b) => new TextDecoder().decode(u8.subarray(a, b));
  try {
    if (format === 'glb' || format === 'gltf') {
      let json;
      if (format === 'glb') {
        const view = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
        json = JSON.parse(text(20, 20 + view.getUint32(12, true)));
      } else {
        json = JSON.parse(text(0, u8.length));
      }
      const attributes = new Set(), extensions = new Set(json.extensionsUsed ?? []);
      let primitives = 0, quantized = false;
      for (const m of json.meshes ?? []) {
        for (const p of m.primitives ?? []) {
          ++primitives;
          for (const [name, a] of Object.entries(p.attributes ?? {})) {
            attributes.add(name);
            const acc = json.accessors?.[a];
            if (name === 'POSITION' && acc && acc.componentType !== 5126) quantized = true;
          }
        }
      }
      const compression = extensions.has('KHR_draco_mesh_compression') ? 'Draco'
        : extensions.has('EXT_meshopt_compression') ? 'meshopt' : 'none';
      return { meshes: `${count(json.meshes?.length ?? 0)} ${json.meshes?.length === 1 ? 'mesh' : 'meshes'}, ${count(primitives)} ${primitives === 1 ? 'primitive' : 'primitives'}, ${count(json.nodes?.length ?? 0)} nodes`,
               attributes: [...attributes].join(', ') || 'none', compression: `${compression}${quantized ? ', quantized positions' : ''}`,
               extras: [...extensions].join(', ') };
    }
    if (format === 'ply') {
      const head = text(0, Math.min(u8.length, 4096));
      const end = head.indexOf('end_header');
      const lines = head.slice(0, end < 0 ? head.length : end).split('\n');
      const props = lines.filter((l) => l.startsWith('property') && !l.includes('list')).map((l) => l.trim().split(/\s+/).pop());
      const encoding = lines.find((l) => l.startsWith('format'))?.split(/\s+/)[1] ?? 'unknown';
      return { meshes: '1 mesh', attributes: props.join(', '), compression: `none (${encoding.replace('_', ' ')})` };
    }
    if (format === 'off') {
      const word = /^\s*([A-Z]*OFF)/.exec(text(0, 16))?.[1] ?? 'OFF';
      return { meshes: '1 mesh', attributes: ['positions', word.includes('N') ? 'normals' : '', word.startsWith('C') ? 'colours' : ''].filter(Boolean).join(', '), compression: 'none (text)' };
    }
    if (format === 'obj') {
      const t = text(0, u8.length);
      const has = (re) => re.test(t);
      return { meshes: `${Math.max(1, (t.match(/^[og] /gm) ?? []).length)} groups`, attributes: ['positions', has(/^vn /m) ? 'normals' : '', has(/^vt /m) ? 'texture coordinates' : ''].filter(Boolean).join(', '), compression: 'none (text)' };
    }
    if (format === 'stl') {
      const ascii = text(0, 5) === 'solid' && text(0, Math.min(u8.length, 512)).includes('facet');
      return { meshes: '1 mesh (separate triangles)', attributes: 'positions, face normals', compression: `none (${ascii ? 'text' : 'binary'})` };
    }
    if (format === 'drc') return { meshes: '1 mesh', attributes: 'positions (Draco)', compression: 'Draco' };
  } catch {
    // A header the page cannot read: the panel says so (the server read the file).
  }
  return { meshes: 'not read by the page', attributes: '', compression: '' };
}

// The output panel: input and output side by side, and the server's checks.
export function outputPanel(input, output, job) {
  const r = job.result;
  const table = el('table', { className: 'output-table' });
  table.createTHead().insertRow().append(el('th', { textContent: '' }), el('th', { textContent: 'Input' }), el('th', { textContent: 'Output' }));
  const body = table.createTBody();
  const row = (k, a, b) => body.insertRow().append(el('th', { textContent: k, scope: 'row' }), el('td', { textContent: a }), el('td', { textContent: b }));
  row('Format', formatName(input.format), formatName(r.format));
  row('Size', bytesText(job.input_bytes), `${bytesText(r.bytes)} (${num((100 * r.bytes) / (job.input_bytes || 1))} %)`);
  row('Holds', input.contents.meshes, output.contents.meshes);
  row('Attributes', input.contents.attributes, output.contents.attributes);
  const named = { none: 'none', draco: 'Draco', meshopt: 'meshopt' };
  row('Compression', input.contents.compression, output.contents.compression || named[r.compression] || r.compression);
  row('Mesh', input.info ? `${count(input.info.vertices)} vertices · ${count(input.info.faces)} faces` : 'not drawn', `${count(r.vertices)} vertices · ${count(r.faces)} faces`);
  const server = [`read ${r.reports.length} ${r.reports.length === 1 ? 'surface' : 'surfaces'}, denoised each and wrote them back with the same faces (only positions change)`, ...r.notes];
  const browser = [];
  if (input.info) {
    browser.push(input.info.open_edges === 0 ? 'the input is closed (no open edges)' : `the input has ${count(input.info.open_edges)} open edges`);
    if (input.info.non_manifold_edges) browser.push(`it has ${count(input.info.non_manifold_edges)} non-manifold edges`);
  }
  const list = (items) => el('ul', { className: 'checks' }, ...items.map((c) => el('li', { textContent: c })));
  return [table, el('h3', { textContent: 'What the server checked and did' }), list(server),
          ...(browser.length ? [el('h3', { textContent: 'Read in this browser' }), list(browser)] : [])];
}
