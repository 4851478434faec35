// Running one job to its end, for the page's run and for the strengths side by side: sending the
// file and following the job, each tried again with backoff while the server cannot be reached
// (decision 66); long polls start at least POLL_GAP_MS apart.
import { isUnreachable, pollJob, submitJob } from './api.js';

export const POLL_S = 0.5;         // long-poll window: progress is redrawn at least this often
const POLL_GAP_MS = 300;           // at least this long between two polls' starts (at most ~3 a second)
const RETRY_MS = [1000, 2000, 4000, 8000, 10_000];  // waits between tries when the server cannot be reached

export const sleep = (ms, signal) => new Promise((resolve, reject) => {
  if (signal?.aborted) { reject(signal.reason); return; }
  const timer = setTimeout(resolve, ms);
  signal?.addEventListener('abort', () => { clearTimeout(timer); reject(signal.reason); }, { once: true });
});

// Waits before try `attempt + 2`; onRetry(attempt, ms) says so first.
async function retryWait(attempt, signal, onRetry) {
  const wait = RETRY_MS[Math.min(attempt, RETRY_MS.length - 1)];
  onRetry?.(attempt, wait);
  await sleep(wait, signal);
}

// POST /v1/jobs until the server answers; an answer that refuses is thrown (ApiError).
// hooks: {onUpload(sent, total), onRetry(attempt, waitMs), onSent()}.
export async function sendJob(file, paramsText, signal, hooks = {}) {
  for (let attempt = 0; ; ++attempt) {
    try {
      const job = await submitJob(file, paramsText, { signal, onUpload: hooks.onUpload });
      hooks.onSent?.();
      return job;
    } catch (e) {
      if (!isUnreachable(e)) throw e;
      await retryWait(attempt, signal, hooks.onRetry);
    }
  }
}

// Long polls until the job ends; returns its last state. hooks: {onProgress(job) (before each
// poll), onRetry(attempt, waitMs), onBack() (an answer after a retry)}.
export async function followJob(job, signal, hooks = {}) {
  let lastPoll = 0;
  for (let attempt = 0; job.state === 'queued' || job.state === 'running';) {
    hooks.onProgress?.(job);
    const gap = POLL_GAP_MS - (performance.now() - lastPoll);
    if (gap > 0) await sleep(gap, signal);
    lastPoll = performance.now();
    try {
      job = await pollJob(job.id, POLL_S, signal);
      if (attempt > 0) hooks.onBack?.();
      attempt = 0;
    } catch (e) {
      if (!isUnreachable(e)) throw e;
      await retryWait(attempt++, signal, hooks.onRetry);
    }
  }
  return job;
}
