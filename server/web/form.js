// The parameter form, generated from GET /v1/params: one row per field of its JSON Schema
// (names, types, ranges, defaults, descriptions) with the units and the paper's ranges of its
// `parameters` list. A field left empty is not sent (auto chooses it, or its default applies); a
// value entered is sent and kept (pinned). Every row carries data-field="name" (output fields
// "output.name"), so a test can compare the form with /v1/params.

const el = (tag, props = {}, ...children) => {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
};

function formatNumber(x) {
  return Math.abs(x) >= 1e6 || (x !== 0 && Math.abs(x) < 1e-3) ? x.toExponential() : String(+x.toPrecision(6));
}

export class ParamForm {
  // params: the body of GET /v1/params; schema: GET /v1/params/schema, the same document with its
  // fields in the order of the file (a JSON object's order does not survive the server's JSON
  // library). containers: {main, more, output} elements.
  constructor(params, schema, containers) {
    this.schema = schema;
    this.specs = new Map(params.parameters.map((p) => [p.name, p]));
    // The fields auto mode chooses are the ones its defaults leave out (server/params_json.h).
    this.autoChosen = new Set(Object.keys(this.schema.properties)
      .filter((name) => name !== 'output' && !(name in params.defaults)));
    this.rows = new Map();  // path -> {control, kind, prop}
    for (const [name, prop] of Object.entries(this.schema.properties)) {
      if (name === 'output' && prop.type === 'object') {
        for (const [sub, subProp] of Object.entries(prop.properties)) this.addRow(containers.output, `output.${sub}`, sub, subProp);
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
      for (const v of prop.enum) {
        control.append(el('option', { value: JSON.stringify(v), textContent: v === null ? 'same as input' : String(v) }));
      }
    } else if (types.includes('boolean')) {
      kind = 'enum';
      control = el('select', { id });
      control.append(el('option', { value: '' }), el('option', { value: 'true', textContent: 'on' }),
                     el('option', { value: 'false', textContent: 'off' }));
    } else if (types.includes('integer') || types.includes('number')) {
      kind = types.includes('integer') ? 'integer' : 'number';
      control = el('input', { id, type: 'text', inputMode: kind === 'integer' ? 'numeric' : 'decimal', autocomplete: 'off' });
    } else {
      kind = 'json';  // a field of a type this form has no widget for: its JSON value
      control = el('input', { id, type: 'text', autocomplete: 'off', spellcheck: false });
    }
    control.name = path;
    control.addEventListener('input', () => this.validateRow(path));
    control.addEventListener('change', () => { this.validateRow(path); if (path === 'mode') this.refreshPlaceholders(); });

    const range = prop.minimum !== undefined ? `[${formatNumber(prop.minimum)}, ${formatNumber(prop.maximum)}]` : '';
    const unit = spec?.unit ? ` ${spec.unit}` : '';
    const paper = spec && (spec.paper_minimum !== spec.minimum || spec.paper_maximum !== spec.maximum)
      ? `; paper: [${formatNumber(spec.paper_minimum)}, ${formatNumber(spec.paper_maximum)}]` : '';
    const help = el('small', { id: `${id}-help`, className: 'help', textContent: prop.description ?? '' });
    const meta = el('span', { className: 'meta', textContent: `${range}${unit}${paper}` });
    control.setAttribute('aria-describedby', `${id}-help`);
    const row = el('div', { className: 'field' },
      el('label', { htmlFor: id }, el('code', { textContent: name }), meta), control, help);
    row.dataset.field = path;
    container.append(row);
    this.rows.set(path, { control, kind, prop, row });
  }

  mode() {
    const chosen = this.rows.get('mode')?.control.value;
    return chosen ? JSON.parse(chosen) : this.schema.properties.mode?.default;
  }

  // Empty fields say what they will be: "auto" where auto chooses, else the default.
  refreshPlaceholders() {
    const auto = this.mode() === 'auto';
    for (const [path, { control, kind, prop }] of this.rows) {
      const chosen = auto && this.autoChosen.has(path);
      const fallback = prop.default === undefined ? '' : prop.default === null ? 'same as input'
        : typeof prop.default === 'boolean' ? (prop.default ? 'on' : 'off')
        : typeof prop.default === 'number' ? formatNumber(prop.default) : String(prop.default);
      if (kind === 'enum') control.options[0].textContent = chosen ? 'auto (chosen per surface)' : `${fallback} (default)`;
      else control.placeholder = chosen ? 'auto' : `default: ${fallback}`;
    }
  }

  // Checks one field against its schema; marks it and returns an error text or null.
  validateRow(path) {
    const { control, kind, prop, row } = this.rows.get(path);
    const text = control.value.trim();
    let error = null;
    if (text !== '' && (kind === 'integer' || kind === 'number')) {
      const ok = kind === 'integer' ? /^\d+$/.test(text) : /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(text);
      const x = Number(text);
      if (!ok) error = kind === 'integer' ? 'a whole number' : 'a number';
      else if (x < prop.minimum || x > prop.maximum) error = `from ${formatNumber(prop.minimum)} to ${formatNumber(prop.maximum)}`;
    } else if (text !== '' && kind === 'json') {
      try { JSON.parse(text); } catch { error = 'a JSON value'; }
    }
    this.markRow(path, error ? `${path} must be ${error}` : null);
    return error;
  }

  markRow(path, message) {
    const entry = this.rows.get(path);
    if (!entry) return;
    entry.row.classList.toggle('invalid', Boolean(message));
    entry.control.setAttribute('aria-invalid', message ? 'true' : 'false');
    entry.row.querySelector('.field-error')?.remove();
    if (message) entry.row.append(el('small', { className: 'field-error', textContent: message }));
  }

  valid() {
    let ok = true;
    for (const path of this.rows.keys()) if (this.validateRow(path)) ok = false;
    return ok;
  }

  // The parameters as the JSON text the API takes: only the fields given. Integers are written
  // as typed (kmeans_seed may exceed 2^53).
  paramsText() {
    const top = [], output = [];
    for (const [path, { control, kind }] of this.rows) {
      const text = control.value.trim();
      if (text === '') continue;
      const value = kind === 'integer' ? text : kind === 'number' ? JSON.stringify(Number(text)) : kind === 'json' ? JSON.stringify(JSON.parse(text)) : text;
      const [head, sub] = path.split('.');
      if (sub) output.push(`${JSON.stringify(sub)}:${value}`);
      else top.push(`${JSON.stringify(head)}:${value}`);
    }
    if (output.length) top.push(`"output":{${output.join(',')}}`);
    return `{${top.join(',')}}`;
  }

  reset() {
    for (const [path, { control }] of this.rows) {
      control.value = '';
      this.markRow(path, null);
    }
    this.refreshPlaceholders();
  }

  // The server named a field in its problem: show the message there.
  showProblemField(problem) {
    if (problem?.field && this.rows.has(problem.field)) {
      this.markRow(problem.field, problem.detail);
      const { row, control } = this.rows.get(problem.field);
      if (row.closest('details')) row.closest('details').open = true;
      control.focus();
    }
  }
}
