// The parameter form. First a simple choice, the strength (auto, light, medium, strong) and the
// output container; under "Advanced", one row per field of GET /v1/params' JSON Schema (names,
// types, ranges, defaults, a short description) with the units and the paper's ranges of its
// `parameters` list. A field left empty is not sent (auto chooses it, or the strength's value or
// the default applies); a value entered is sent and kept (pinned). Every row carries
// data-field="name" (output fields "output.name"), so a test can compare the form with
// /v1/params. Deprecated fields, and values the server always refuses, are not offered.

const el = (tag, props = {}, ...children) => {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
};

function formatNumber(x) {
  return Math.abs(x) >= 1e6 || (x !== 0 && Math.abs(x) < 1e-3) ? x.toExponential() : String(+x.toPrecision(6));
}

// The strengths of the simple form: manual-mode parameter sets within the paper's ranges
// (Table 1: sigma in [20, 50] degrees, iterations in [5, 100]); "auto" lets the server choose per
// surface. Listed in server/web/README.md; the form says what each one sends.
export const STRENGTHS = {
  auto: { label: 'Auto', params: {} },
  light: { label: 'Light', params: { mode: 'manual', alpha: 0.05, sigma_theta: 20, n_aniso: 1, sigma_gamma: 20, n_normal: 5, n_vertex: 5 } },
  medium: { label: 'Medium', params: { mode: 'manual', alpha: 0.1, sigma_theta: 30, n_aniso: 2, sigma_gamma: 30, n_normal: 20, n_vertex: 10 } },
  strong: { label: 'Strong', params: { mode: 'manual', alpha: 0.2, sigma_theta: 45, n_aniso: 6, sigma_gamma: 45, n_normal: 60, n_vertex: 30 } },
};

// Values the schema lists that the server refuses whatever the input (422: the schema's own
// description says so); offering them would only produce an error.
const NEVER_WORKS = { 'output.compression': ['meshopt'] };

// What the mode values mean, in a line each (the schema's description is written for the API).
const MODE_LABELS = { auto: 'auto: chosen per surface', search: 'search: auto, then refined (slow)', manual: 'manual: the values given', none: 'none: convert only' };
const MODE_HELP = 'How the method parameters are chosen. Auto reads each surface and a model trained offline picks the settings; manual uses the fields below (defaults for empty ones).';

// The description's first clause, for a one-line help text (ranges and units are shown apart).
function shortHelp(text = '') {
  const first = text.split(/;\s/)[0];
  return first.length > 140 ? `${first.slice(0, first.lastIndexOf(' ', 137))}…` : first;
}

export class ParamForm {
  // params: the body of GET /v1/params; schema: GET /v1/params/schema, the same document with its
  // fields in the order of the file (a JSON object's order does not survive the server's JSON
  // library). containers: {strength, strengthHelp, format, main, more, output} elements.
  constructor(params, schema, containers) {
    this.schema = schema;
    this.specs = new Map(params.parameters.map((p) => [p.name, p]));
    // The fields auto mode chooses are the ones its defaults leave out (service/params_json.h).
    this.autoChosen = new Set(Object.keys(this.schema.properties)
      .filter((name) => name !== 'output' && !(name in params.defaults)));
    this.rows = new Map();  // path -> {control, kind, prop, row}
    this.onChange = () => {};
    this.strength = containers.strength;
    this.strengthHelp = containers.strengthHelp;
    for (const [key, { label }] of Object.entries(STRENGTHS)) this.strength.append(el('option', { value: key, textContent: label }));
    this.strength.addEventListener('change', () => { this.refreshPlaceholders(); this.onChange(); });
    for (const [name, prop] of Object.entries(this.schema.properties)) {
      if (prop.deprecated) continue;
      if (name === 'output' && prop.type === 'object') {
        for (const [sub, subProp] of Object.entries(prop.properties)) {
          if (!subProp.deprecated) this.addRow(sub === 'format' ? containers.format : containers.output, `output.${sub}`, sub, subProp);
        }
      } else {
        this.addRow(this.autoChosen.has(name) || name === 'mode' ? containers.main : containers.more, name, name, prop);
      }
    }
    this.refreshPlaceholders();
  }

  addRow(container, path, name, prop) {
    const id = `field-${path.replace('.', '-')}`;
    const spec = this.specs.get(name);
    const types = [].concat(prop.type ?? []);
    let control, kind;
    if (prop.enum) {
      kind = 'enum';
      control = el('select', { id });
      control.append(el('option', { value: '' }));  // not sent; its label is set by refreshPlaceholders
      const never = NEVER_WORKS[path] ?? [];
      for (const v of prop.enum) {
        if (v === prop.default || never.includes(v)) continue;  // the empty option stands for the default
        const text = v === null ? 'same as input' : path === 'mode' ? MODE_LABELS[v] ?? v : String(v);
        control.append(el('option', { value: JSON.stringify(v), textContent: text }));
      }
    } else if (types.includes('boolean')) {
      kind = 'enum';
      control = el('select', { id });
      control.append(el('option', { value: '' }));
      for (const v of [true, false]) if (v !== prop.default) control.append(el('option', { value: String(v), textContent: v ? 'on' : 'off' }));
    } else if (types.includes('integer') || types.includes('number')) {
      kind = types.includes('integer') ? 'integer' : 'number';
      control = el('input', { id, type: 'text', inputMode: kind === 'integer' ? 'numeric' : 'decimal', autocomplete: 'off' });
    } else {
      kind = 'json';  // a field of a type this form has no widget for: its JSON value
      control = el('input', { id, type: 'text', autocomplete: 'off', spellcheck: false });
    }
    control.name = path;
    control.addEventListener('input', () => { this.validateRow(path); this.onChange(); });
    control.addEventListener('change', () => { this.validateRow(path); if (path === 'mode') this.refreshPlaceholders(); this.onChange(); });

    // A range as people read it: an upper bound beyond any sensible value (a 64-bit seed) is left out.
    const range = prop.minimum === undefined ? ''
      : prop.maximum === undefined || prop.maximum > 1e9 ? `≥ ${formatNumber(prop.minimum)}`
      : `${formatNumber(prop.minimum)} – ${formatNumber(prop.maximum)}`;
    const unit = spec?.unit && spec.unit !== 'iterations' ? ` ${spec.unit}` : '';
    const paper = spec && spec.paper_minimum !== undefined && (spec.paper_minimum !== spec.minimum || spec.paper_maximum !== spec.maximum)
      ? ` · paper ${formatNumber(spec.paper_minimum)} – ${formatNumber(spec.paper_maximum)}` : '';
    const help = el('small', { id: `${id}-help`, className: 'help', textContent: path === 'mode' ? MODE_HELP : shortHelp(prop.description) });
    const meta = el('span', { className: 'meta', textContent: `${range}${unit}${paper}` });
    control.setAttribute('aria-describedby', `${id}-help`);
    const title = path === 'output.format' ? 'Output format' : name;
    const row = el('div', { className: 'field' },
      el('label', { htmlFor: id }, path === 'output.format' ? title : el('code', { textContent: name }), meta), control, help);
    row.dataset.field = path;
    container.append(row);
    this.rows.set(path, { control, kind, prop, row });
  }

  preset() { return STRENGTHS[this.strength.value]?.params ?? {}; }

  // The mode that will run: the field's, else the strength's, else the default.
  mode() {
    const chosen = this.rows.get('mode')?.control.value;
    return chosen ? JSON.parse(chosen) : this.preset().mode ?? this.schema.properties.mode?.default;
  }

  // Empty fields say what they will be: "auto" where auto chooses, the strength's value, or the default.
  refreshPlaceholders() {
    const auto = this.mode() === 'auto';
    const preset = this.preset();
    for (const [path, { control, kind, prop }] of this.rows) {
      const chosen = auto && this.autoChosen.has(path);
      const base = path in preset ? preset[path] : prop.default;
      const fallback = base === undefined ? '' : base === null ? 'same as input'
        : typeof base === 'boolean' ? (base ? 'on' : 'off')
        : typeof base === 'number' ? formatNumber(base) : path === 'mode' ? MODE_LABELS[base] ?? base : String(base);
      const from = path in preset ? `${this.strength.value}` : 'default';
      if (kind === 'enum') control.options[0].textContent = chosen ? 'auto (chosen per surface)' : path === 'output.format' ? fallback : `${fallback} (${from})`;
      else control.placeholder = chosen ? 'auto' : `${fallback} (${from})`;
    }
    const p = Object.entries(preset).filter(([k]) => k !== 'mode').map(([k, v]) => `${k} ${v}`).join(', ');
    this.strength.title = p ? `Sends mode manual with ${p}` : 'The server measures the noise of each surface and chooses the parameters';
    this.strengthHelp.textContent = p
      ? `Manual: ${preset.n_normal} normal and ${preset.n_vertex} vertex iterations, ${preset.sigma_gamma}° (Help lists all).`
      : 'The server measures each surface\'s noise and chooses.';
  }

  // Checks one field against its schema; marks it and returns an error text or null.
  validateRow(path) {
    const { control, kind, prop } = this.rows.get(path);
    const text = control.value.trim();
    let error = null;
    if (text !== '' && (kind === 'integer' || kind === 'number')) {
      const ok = kind === 'integer' ? /^\d+$/.test(text) : /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(text);
      const x = Number(text);
      if (!ok) error = kind === 'integer' ? 'a whole number' : 'a number';
      else if (x < prop.minimum || x > prop.maximum) error = prop.maximum > 1e9 ? `at least ${formatNumber(prop.minimum)}` : `from ${formatNumber(prop.minimum)} to ${formatNumber(prop.maximum)}`;
    } else if (text !== '' && kind === 'json') {
      try { JSON.parse(text); } catch { error = 'a JSON value'; }
    }
    this.markRow(path, error ? `${path} must be ${error}.` : null);
    return error ? `${path} must be ${error}` : null;
  }

  markRow(path, message) {
    const entry = this.rows.get(path);
    if (!entry) return;
    entry.row.classList.toggle('invalid', Boolean(message));
    entry.control.setAttribute('aria-invalid', message ? 'true' : 'false');
    entry.row.querySelector('.field-error')?.remove();
    if (message) entry.row.append(el('small', { className: 'field-error', textContent: message }));
  }

  // Every field checked and marked; the first wrong one is shown (its section opened) and, unless
  // focus is false, focused. Returns {field, message} of that one, or null when all are valid.
  firstInvalid({ focus = true } = {}) {
    let first = null;
    for (const path of this.rows.keys()) {
      const message = this.validateRow(path);
      if (message && !first) first = { field: path, message };
    }
    if (first && focus) this.focus(first.field);
    return first;
  }

  // Whether any field is wrong (each is marked), without moving the focus.
  anyInvalid() {
    let bad = false;
    for (const path of this.rows.keys()) if (this.validateRow(path)) bad = true;
    return bad;
  }

  focus(path) {
    const { row, control } = this.rows.get(path);
    for (let d = row.closest('details'); d; d = d.parentElement?.closest('details')) d.open = true;
    // Scrolled to just below the sticky action bar, which would otherwise cover it (measured
    // now: the bar grows with the error it shows), with its label and help in view.
    const bar = document.getElementById('actionbar');
    row.style.scrollMarginTop = `${(bar ? bar.getBoundingClientRect().height : 0) + 12}px`;
    control.focus({ preventScroll: true });
    row.scrollIntoView({ block: 'start' });
    // The bar is sticky within the scrolling panel (wide) or the page (narrow): where its bottom
    // still lies below the row's top, scroll the difference.
    const covered = bar ? bar.getBoundingClientRect().bottom + 8 - row.getBoundingClientRect().top : 0;
    if (covered > 0) {
      const scroller = row.closest('.panel');
      if (scroller && scroller.scrollHeight > scroller.clientHeight && getComputedStyle(scroller).display !== 'contents') scroller.scrollTop -= covered;
      else window.scrollBy(0, -covered);
    }
  }

  // The parameters as the JSON text the API takes: the strength's set, then the fields given
  // (which win). Integers are written as typed (kmeans_seed may exceed 2^53).
  paramsText() {
    const top = new Map(Object.entries(this.preset()).map(([k, v]) => [k, JSON.stringify(v)]));
    const output = [];
    for (const [path, { control, kind }] of this.rows) {
      const text = control.value.trim();
      if (text === '') continue;
      const value = kind === 'integer' ? text : kind === 'number' ? JSON.stringify(Number(text)) : kind === 'json' ? JSON.stringify(JSON.parse(text)) : text;
      const [head, sub] = path.split('.');
      if (sub) output.push(`${JSON.stringify(sub)}:${value}`);
      else top.set(head, value);
    }
    const parts = [...top].map(([k, v]) => `${JSON.stringify(k)}:${v}`);
    if (output.length) parts.push(`"output":{${output.join(',')}}`);
    return `{${parts.join(',')}}`;
  }

  // The parameters of a strength alone (its set, or {} for auto), with the output fields given:
  // what the strengths side by side send, so that each result is in the chosen container.
  strengthParamsText(key) {
    const output = [];
    for (const [path, { control }] of this.rows) {
      const text = control.value.trim();
      const [head, sub] = path.split('.');
      if (text !== '' && head === 'output' && sub) output.push(`${JSON.stringify(sub)}:${text}`);
    }
    const parts = Object.entries(STRENGTHS[key].params).map(([k, v]) => `${JSON.stringify(k)}:${JSON.stringify(v)}`);
    if (output.length) parts.push(`"output":{${output.join(',')}}`);
    return `{${parts.join(',')}}`;
  }

  setStrength(key) {
    this.strength.value = key;
    this.refreshPlaceholders();
    this.onChange();
  }

  reset() {
    for (const [path, { control }] of this.rows) {
      control.value = '';
      this.markRow(path, null);
    }
    this.strength.value = 'auto';
    this.refreshPlaceholders();
    this.onChange();
  }

  // The server named a field in its problem: show the message there.
  showProblemField(problem) {
    if (problem?.field && this.rows.has(problem.field)) {
      this.markRow(problem.field, problem.detail);
      this.focus(problem.field);
    }
  }
}
