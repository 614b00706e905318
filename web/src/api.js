// api.js — the job flow of the documented API (schemas/openapi.json):
//   POST /v1/jobs with "Prefer: wait=2": 200 is the result itself; 202 gives the job, its
//   Location and Retry-After; GET Location (every Retry-After seconds) reports progress until
//   the job is done, failed or canceled; the result is then GET from the job's "result" URL
//   (/v1/results/{hash}).  DELETE Location cancels this submission.
// Errors are application/problem+json: a Problem keeps "status", "title", "detail" and, for an
// invalid request, "path".

export class Problem extends Error {
  constructor(status, body) {
    super(body && body.detail ? body.detail : `HTTP ${status}`);
    this.status = status;
    this.title = (body && body.title) || '';
    this.detail = (body && body.detail) || '';
    this.path = (body && body.path) || '';
  }
}

export class Canceled extends Error {
  constructor() { super('the job was canceled'); }
}

async function problemOf(r) {
  const t = await r.text();
  try {
    const o = JSON.parse(t);
    if (o && typeof o === 'object') return new Problem(r.status, o);
  } catch { /* not JSON */ }
  return new Problem(r.status, { title: r.statusText, detail: t.slice(0, 300) || r.statusText });
}

// Retry-After in seconds (delta-seconds or an HTTP date), else dflt; within [0.2, 60].
export function retryAfter(r, dflt) {
  const h = r.headers.get('Retry-After');
  if (!h) return dflt;
  let s = /^\s*\d+\s*$/.test(h) ? Number(h) : (Date.parse(h) - Date.now()) / 1000;
  if (!Number.isFinite(s)) return dflt;
  return Math.min(60, Math.max(0.2, s));
}

// The result's hash from a 200 answer to a POST (Content-Location: /v1/results/HASH, or its
// ETag "HASH").
function hashOf(r) {
  const cl = r.headers.get('Content-Location') || '';
  const m = /\/v1\/results\/([0-9a-f]{64})/.exec(cl) || /"([0-9a-f]{64})/.exec(r.headers.get('ETag') || '');
  return m ? m[1] : '';
}

// Starts a job for body (a JSON string).  onJob(job) hears every job status read (202 and each
// poll).  Returns {done, cancel}: done resolves to {hash, buffer (the result's JSON bytes),
// job (the last status, or null when the POST answered 200), waited (seconds polled)}, or
// rejects with a Problem, a Canceled or a network error; cancel() DELETEs the submission (at
// once, or as soon as the POST has answered).
export function startJob(body, onJob) {
  let loc = null, cancelAsked = false, canceled = false, wake = null;
  const sleep = (s) => new Promise((res) => {
    const t = setTimeout(() => { wake = null; res(); }, s * 1000);
    wake = () => { clearTimeout(t); wake = null; res(); };
  });
  const del = async () => {
    const r = await fetch(loc, { method: 'DELETE' });
    if (r.ok || r.status === 409) {
      let job = null;
      try { job = await r.json(); } catch { /* a problem */ }
      if (r.ok || (job && /canceled/.test(job.detail || ''))) canceled = true;
      if (job && job.state) onJob(job);
    } else throw await problemOf(r);
    if (wake) wake();
  };
  const done = (async () => {
    const r = await fetch('/v1/jobs', {
      method: 'POST', body,
      headers: { 'Content-Type': 'application/json', Accept: 'application/json', Prefer: 'wait=2' },
    });
    if (r.status === 200) return { hash: hashOf(r), buffer: await r.arrayBuffer(), job: null };
    if (r.status !== 202) throw await problemOf(r);
    let job = await r.json();
    loc = r.headers.get('Location') || `/v1/jobs/${job.id}`;
    let retry = retryAfter(r, 1);
    onJob(job);
    if (cancelAsked) await del();
    for (;;) {
      if (canceled || job.state === 'canceled') throw new Canceled();
      if (job.state === 'failed') throw new Problem(job.error?.status || 500, job.error);
      if (job.state === 'done') break;
      await sleep(retry);
      if (canceled) throw new Canceled();
      const g = await fetch(loc, { headers: { Accept: 'application/json' } });
      if (!g.ok) throw await problemOf(g);
      retry = retryAfter(g, retry);
      job = await g.json();
      onJob(job);
    }
    const res = await fetch(job.result || `/v1/results/${job.hash}`, { headers: { Accept: 'application/json' } });
    if (!res.ok) throw await problemOf(res);
    return { hash: job.hash, buffer: await res.arrayBuffer(), job };
  })();
  const cancel = async () => {
    cancelAsked = true;
    if (loc && !canceled) await del();
  };
  return { done, cancel, jobUrl: () => loc };
}
