// The service's HTTP API as the page uses it: same origin, RFC 9457 problems turned into
// ApiError, and the bearer token asked for once (on the first 401) and kept for the tab. Every
// request has a time limit (nothing waits forever); the upload and the download report their
// progress; a job can be cancelled as the page goes away (keepalive).

const TOKEN_KEY = 'meshdenoise.token';
const REQUEST_LIMIT_MS = 30_000;   // any one answer (a long poll waits 0.5 s of it)
const TRANSFER_IDLE_MS = 30_000;   // an upload or download with no byte moving for this long

// An error answer of the API (problem+json), or a failure described the same way, in words
// for people (never a parser's message).
export class ApiError extends Error {
  constructor(problem) {
    super(`${problem.title}: ${problem.detail}`);
    this.problem = problem;
  }
}

let askToken = async () => null;  // set by the page: shows the token dialog, resolves to the token

export function onTokenNeeded(ask) { askToken = ask; }
export function token() { return sessionStorage.getItem(TOKEN_KEY); }

const unreachable = () => Object.assign(new ApiError({ status: 0, title: 'The server cannot be reached', detail: 'Check that meshdenoise-server is running and reachable, then try again.' }), { unreachable: true });
const tooSlow = () => Object.assign(new ApiError({ status: 0, title: 'The server stopped answering', detail: `No answer for ${REQUEST_LIMIT_MS / 1000} s; the page gave up waiting. Try again.` }), { unreachable: true });

// Whether an error means no answer came at all (the server is down, restarting or cut off), as
// opposed to an answer that refused: the page may try again later.
export const isUnreachable = (e) => e instanceof ApiError && e.unreachable === true;

// A problem from an error answer's text; an answer that is not problem+json (a proxy's page)
// is described by its status.
function problemFrom(status, statusText, type, text) {
  if ((type ?? '').startsWith('application/problem+json')) {
    try {
      const p = JSON.parse(text);
      if (p && typeof p.title === 'string') return p;
    } catch { /* described below */ }
  }
  return { status, title: `The server answered HTTP ${status}`, detail: statusText || 'It gave no explanation.' };
}

// fetch() with the token and a time limit; a 401 asks for a token once and retries. Throws
// ApiError on a 4xx/5xx or a network failure; AbortError when `signal` aborts.
export async function request(path, options = {}) {
  for (let attempt = 0; ; ++attempt) {
    const headers = new Headers(options.headers ?? {});
    if (token()) headers.set('Authorization', `Bearer ${token()}`);
    // The limit is on the answer's arrival (its headers): a large body may take longer.
    const limit = new AbortController();
    const timer = setTimeout(() => limit.abort(), REQUEST_LIMIT_MS);
    const signal = options.signal ? AbortSignal.any([options.signal, limit.signal]) : limit.signal;
    let response;
    try {
      response = await fetch(path, { ...options, headers, signal });
    } catch (e) {
      if (options.signal?.aborted) throw options.signal.reason ?? e;
      throw limit.signal.aborted ? tooSlow() : unreachable();
    } finally {
      clearTimeout(timer);
    }
    if (response.ok) return response;
    const problem = problemFrom(response.status, response.statusText, response.headers.get('Content-Type'), await response.text().catch(() => ''));
    if (response.status === 401 && attempt < 2) {
      const given = await askToken(attempt > 0);
      if (given) {
        sessionStorage.setItem(TOKEN_KEY, given);
        continue;
      }
    }
    throw new ApiError(problem);
  }
}

export async function getJson(path, options) {
  const response = await request(path, options);
  try {
    return await response.json();
  } catch {
    throw new ApiError({ status: 0, title: 'The server\'s answer could not be read', detail: `${path} did not answer with JSON.` });
  }
}

// POST /v1/jobs as a multipart form (mesh + params), through XMLHttpRequest: fetch() reports no
// upload progress. onUpload(sent, total) while the bytes go. The part is sent as
// application/octet-stream with its file name: the server recognises the format from the name,
// else from the bytes.
export async function submitJob(file, paramsText, { signal, onUpload }) {
  for (let attempt = 0; ; ++attempt) {
    const form = new FormData();
    form.append('mesh', new Blob([file], { type: 'application/octet-stream' }), file.name);
    form.append('params', paramsText);
    const xhr = new XMLHttpRequest();
    const done = new Promise((resolve, reject) => {
      let idle;
      const touch = () => { clearTimeout(idle); idle = setTimeout(() => { xhr.abort(); reject(tooSlow()); }, TRANSFER_IDLE_MS); };
      const abort = () => xhr.abort();
      signal?.addEventListener('abort', abort, { once: true });
      const end = () => { clearTimeout(idle); signal?.removeEventListener('abort', abort); };
      xhr.upload.onprogress = (e) => { touch(); onUpload?.(e.loaded, e.lengthComputable ? e.total : file.size); };
      xhr.onload = () => { end(); resolve(); };
      xhr.onerror = () => { end(); reject(unreachable()); };
      xhr.onabort = () => { end(); reject(signal?.aborted ? signal.reason : tooSlow()); };
      touch();
    });
    xhr.open('POST', '/v1/jobs');
    if (token()) xhr.setRequestHeader('Authorization', `Bearer ${token()}`);
    xhr.send(form);
    await done;
    if (xhr.status === 202 || xhr.status === 200) {
      try { return JSON.parse(xhr.responseText); } catch { throw new ApiError({ status: 0, title: 'The server\'s answer could not be read', detail: 'POST /v1/jobs did not answer with JSON.' }); }
    }
    if (xhr.status === 401 && attempt < 2) {
      const given = await askToken(attempt > 0);
      if (given) {
        sessionStorage.setItem(TOKEN_KEY, given);
        continue;
      }
    }
    throw new ApiError(problemFrom(xhr.status, xhr.statusText, xhr.getResponseHeader('Content-Type'), xhr.responseText));
  }
}

// Long poll: answers when the job finishes or after `seconds` with its progress.
export async function pollJob(id, seconds, signal) {
  return getJson(`/v1/jobs/${encodeURIComponent(id)}?wait=${seconds}`, { signal });
}

export async function cancelJob(id) {
  await request(`/v1/jobs/${encodeURIComponent(id)}`, { method: 'DELETE' });
}

// As the page goes away (pagehide): a DELETE that outlives the page (keepalive), so an
// abandoned job stops within seconds instead of holding a worker.
export function cancelOnLeave(id) {
  const headers = token() ? { Authorization: `Bearer ${token()}` } : {};
  fetch(`/v1/jobs/${encodeURIComponent(id)}`, { method: 'DELETE', keepalive: true, headers }).catch(() => {});
}

// The result's bytes; onProgress(received, total) as they arrive. The total is the decoded
// size (X-Denoise-Output-Bytes): the body may be gzip-encoded on the wire.
export async function jobResult(id, { signal, onProgress } = {}) {
  const response = await request(`/v1/jobs/${encodeURIComponent(id)}/result`, { signal });
  const total = Number(response.headers.get('X-Denoise-Output-Bytes')) || 0;
  const reader = response.body.getReader();
  const chunks = [];
  let received = 0;
  for (;;) {
    let idle;
    const step = await Promise.race([reader.read(), new Promise((_, reject) => { idle = setTimeout(() => reject(tooSlow()), TRANSFER_IDLE_MS); })])
      .finally(() => clearTimeout(idle));
    if (step.done) break;
    chunks.push(step.value);
    received += step.value.byteLength;
    onProgress?.(received, total);
  }
  const bytes = new Uint8Array(received);
  let at = 0;
  for (const c of chunks) { bytes.set(c, at); at += c.byteLength; }
  return bytes.buffer;
}
