// The service's HTTP API as the page uses it: same origin, RFC 9457 problems turned into
// ApiError, and the bearer token asked for once (on the first 401) and kept for the tab.

const TOKEN_KEY = 'meshdenoise.token';

// An error answer of the API (problem+json), or a network failure described the same way.
export class ApiError extends Error {
  constructor(problem) {
    super(`${problem.title}: ${problem.detail}`);
    this.problem = problem;
  }
}

let askToken = async () => null;  // set by the page: shows the token dialog, resolves to the token

export function onTokenNeeded(ask) { askToken = ask; }
export function token() { return sessionStorage.getItem(TOKEN_KEY); }

async function problemOf(response) {
  const type = response.headers.get('Content-Type') ?? '';
  if (type.startsWith('application/problem+json')) {
    try { return await response.json(); } catch { /* fall through */ }
  }
  return { status: response.status, title: `HTTP ${response.status}`, detail: response.statusText || 'the server gave no detail' };
}

// fetch() with the token; a 401 asks for a token once and retries. Throws ApiError on a 4xx/5xx.
export async function request(path, options = {}) {
  for (let attempt = 0; ; ++attempt) {
    const headers = new Headers(options.headers ?? {});
    if (token()) headers.set('Authorization', `Bearer ${token()}`);
    let response;
    try {
      response = await fetch(path, { ...options, headers });
    } catch (e) {
      if (e.name === 'AbortError') throw e;
      throw new ApiError({ status: 0, title: 'Server unreachable', detail: `${path}: ${e.message}` });
    }
    if (response.ok) return response;
    const problem = await problemOf(response);
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
  return (await request(path, options)).json();
}

// POST /v1/jobs as a multipart form (mesh + params). The part is sent as application/octet-stream
// with its file name: the server recognises the format from the name, else from the bytes, so any
// format it reads works here without the page knowing it.
export async function submitJob(file, paramsText, signal) {
  const form = new FormData();
  form.append('mesh', new Blob([file], { type: 'application/octet-stream' }), file.name);
  form.append('params', paramsText);
  return getJson('/v1/jobs', { method: 'POST', body: form, signal });
}

// Long poll: answers when the job finishes or after `seconds` with its progress.
export async function pollJob(id, seconds, signal) {
  return getJson(`/v1/jobs/${encodeURIComponent(id)}?wait=${seconds}`, { signal });
}

export async function cancelJob(id) {
  await request(`/v1/jobs/${encodeURIComponent(id)}`, { method: 'DELETE' });
}

export async function jobResult(id) {
  return (await request(`/v1/jobs/${encodeURIComponent(id)}/result`)).arrayBuffer();
}
