// Compare with a reference: a clean mesh chosen by the user is sent with the input and with the
// result to POST /v1/compare, which measures each against it with the core's metrics (the
// figures `meshdenoise --metrics` prints: MSAE where the faces match, E_v always) and answers
// each vertex's deviation; the figures go in a table, the result's deviation into the heat map.
import { ApiError, request } from './api.js';
import { num } from './format.js';

const $ = (id) => document.getElementById(id);

async function compareWith(reference, mesh, name, signal) {
  const form = new FormData();
  form.append('reference', new Blob([reference], { type: 'application/octet-stream' }), reference.name);
  form.append('mesh', new Blob([mesh], { type: 'application/octet-stream' }), name);
  const response = await request('/v1/compare', { method: 'POST', body: form, signal });
  return response.json();
}

export class ReferenceComparison {
  // page: {input() -> File, result() -> {blob, name, vertices} or null, heat (HeatMap)}.
  constructor(page) {
    this.page = page;
    this.abort = null;
    $('reference-file').addEventListener('change', () => {
      const file = $('reference-file').files[0];
      $('reference-file').value = '';
      if (file) this.run(file);
    });
  }

  clear() {
    this.abort?.abort();
    this.abort = null;
    $('reference').dataset.state = 'idle';
    $('reference-status').textContent = '';
    $('reference-figures').hidden = true;
    $('reference-rows').replaceChildren();
  }

  async run(file) {
    this.clear();
    const input = this.page.input(), result = this.page.result();
    if (!input || !result) return;
    const abort = this.abort = new AbortController();
    $('reference').dataset.state = 'running';
    $('reference-status').textContent = file.size === 0 ? `${file.name} is empty: choose another file.` : `Measuring against ${file.name} on the server…`;
    if (file.size === 0) { $('reference').dataset.state = 'failed'; return; }
    try {
      const [before, after] = await Promise.all([compareWith(file, input, input.name, abort.signal),
                                                 compareWith(file, result.blob, result.name, abort.signal)]);
      if (this.abort !== abort) return;
      const row = (label, c) => {
        const tr = document.createElement('tr');
        tr.dataset.row = label.toLowerCase();
        tr.dataset.ev = String(c.ev);
        tr.dataset.msae = c.msae_deg2 === null ? '' : String(c.msae_deg2);
        tr.append(Object.assign(document.createElement('th'), { scope: 'row', textContent: label }),
                  Object.assign(document.createElement('td'), { textContent: c.msae_deg2 === null ? 'n/a (other faces)' : num(c.msae_deg2) }),
                  Object.assign(document.createElement('td'), { textContent: num(c.ev) }));
        return tr;
      };
      $('reference-rows').replaceChildren(row('Input', before), row('Result', after));
      $('reference-figures').hidden = false;
      const drawn = after.deviation.length === result.vertices;
      $('reference-status').textContent = `Against ${file.name} (${after.reference.faces.toLocaleString('en')} faces)` +
        `${after.same_faces ? ', the same faces: MSAE and a signed deviation' : ', other faces: E_v and the distance to its surface'}.` +
        (drawn ? ' The heat map shows the result\'s deviation (Reference).' : ' The result\'s vertices differ from the drawn ones, so no deviation map.');
      if (drawn) this.page.heat.setReference({ deviation: Float32Array.from(after.deviation), signed: after.deviation_signed, edge: after.mean_edge_length });
      $('reference').dataset.state = 'done';
    } catch (e) {
      if (e?.name === 'AbortError' || this.abort !== abort) return;
      const p = e instanceof ApiError ? e.problem : { title: 'The comparison failed', detail: '' };
      $('reference-status').textContent = `${file.name} could not be compared: ${p.title}${p.detail ? ` (${p.detail})` : ''}.`;
      $('reference').dataset.state = 'failed';
    }
  }
}
