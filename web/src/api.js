// api.js — the job flow of the documented API (schemas/openapi.json):
//   POST v1/jobs with "Prefer: wait=2" (an XMLHttpRequest, for its upload progress): 200 is the
//   result itself; 202 gives the job and Retry-After; GET v1/jobs/{id} (every Retry-After
//   seconds) reports progress until the job is done, failed or canceled; the result is then
//   GET from v1/results/{hash}, streamed (download progress).  DELETE v1/jobs/{id} cancels
//   this submission.  Every URL is relative to the page (the service may sit under a
//   sub-path behind a proxy).
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

// The result's hash from a 200 answer to a POST (Content-Location: .../v1/results/HASH, or its
// ETag "HASH").
function hashOf(r) {
  const cl = r.headers.get('Content-Location') || '';
  const m = /v1\/results\/([0-9a-f]{64})/.exec(cl) || /"([0-9a-f]{64})/.exec(r.headers.get('ETag') || '');
  return m ? m[1] : '';
}

// The answer of an XMLHttpRequest as much of a fetch Response as this file uses.
function xhrResponse(x) {
  const buf = x.response || new ArrayBuffer(0);
  return {
    status: x.status, statusText: x.statusText, ok: x.status >= 200 && x.status < 300,
    headers: { get: (h) => x.getResponseHeader(h) },
    arrayBuffer: async () => buf,
    text: async () => new TextDecoder().decode(buf),
    json: async () => JSON.parse(new TextDecoder().decode(buf)),
  };
}

// POST body to url with an XMLHttpRequest (a fetch tells nothing of its upload): onSent(loaded,
// total) as the body goes, onGot(loaded, total or 0) as the answer comes; resolves to the
// answer (xhrResponse), rejects with a Canceled when abort() was called, or a network error.
function post(url, body, headers, { onSent, onGot, onUploaded }) {
  const x = new XMLHttpRequest();
  const done = new Promise((resolve, reject) => {
    x.open('POST', url);
    for (const [k, v] of Object.entries(headers)) x.setRequestHeader(k, v);
    x.responseType = 'arraybuffer';
    x.upload.onprogress = (e) => onSent(e.loaded, e.lengthComputable ? e.total : 0);
    x.upload.onload = () => onUploaded();
    x.onprogress = (e) => onGot(e.loaded, e.lengthComputable && !x.getResponseHeader('Content-Encoding') ? e.total : 0);
    x.onload = () => resolve(xhrResponse(x));
    x.onabort = () => reject(new Canceled());
    x.onerror = () => reject(new Error(`POST ${url}: the network failed (no answer)`));
    x.send(body);
  });
  return { done, abort: () => x.abort(), answering: () => x.readyState >= 2 && x.status !== 202 };
}

// GET url as bytes, streamed: onGot(loaded, total) as they come (total: the Content-Length
// when the bytes are not encoded, else 0); signal aborts it (a Canceled).
async function getBytes(url, signal, onGot) {
  let r;
  try {
    r = await fetch(url, { headers: { Accept: 'application/json' }, signal });
  } catch (e) {
    if (signal.aborted) throw new Canceled();
    throw e;
  }
  if (!r.ok) throw await problemOf(r);
  const len = r.headers.get('Content-Encoding') ? 0 : Number(r.headers.get('Content-Length')) || 0;
  if (!r.body) return r.arrayBuffer();
  const reader = r.body.getReader(), parts = [];
  let got = 0;
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      parts.push(value);
      got += value.length;
      onGot(got, len);
    }
  } catch (e) {
    if (signal.aborted) throw new Canceled();
    throw e;
  }
  const out = new Uint8Array(got);
  let k = 0;
  for (const p of parts) { out.set(p, k); k += p.length; }
  return out.buffer;
}

// Starts a job for body (a JSON string) at the service whose root is base (the page's URL: the
// service may be mounted under a sub-path, so every URL here is made from base, never from an
// absolute path the server names).  hooks: onJob(job, jobUrl) hears every job status read (202
// and each poll); onSent(loaded, total) the upload; onGot(loaded, total or 0) the result's
// download.  Returns {done, cancel, jobUrl}: done resolves to {hash, buffer (the result's JSON
// bytes), job (the last status, or null when the POST answered 200)}, or rejects with a
// Problem, a Canceled or a network error; cancel() stops what runs: an upload is aborted (no
// job was made), a job made is DELETEd (at once, or as soon as the POST answers), a download
// is aborted.
export function startJob(base, body, hooks) {
  const { onJob = () => {}, onSent = () => {}, onGot = () => {} } = hooks;
  const at = (p) => new URL(p, base).href;
  let loc = null, cancelAsked = false, canceled = false, wake = null, uploaded = false, xhr = null;
  const ctl = new AbortController();
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
      if (job && job.state) onJob(job, loc);
    } else throw await problemOf(r);
    if (wake) wake();
  };
  const done = (async () => {
    xhr = post(at('v1/jobs'), body,
      { 'Content-Type': 'application/json', Accept: 'application/json', Prefer: 'wait=2' },
      { onSent, onGot, onUploaded: () => { uploaded = true; } });
    const r = await xhr.done;
    xhr = null;
    if (r.status === 200) {
      if (cancelAsked) throw new Canceled();
      return { hash: hashOf(r), buffer: await r.arrayBuffer(), job: null };
    }
    if (r.status !== 202) throw await problemOf(r);
    let job = await r.json();
    loc = at(`v1/jobs/${encodeURIComponent(job.id)}`);
    let retry = retryAfter(r, 1);
    onJob(job, loc);
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
      onJob(job, loc);
    }
    if (cancelAsked) throw new Canceled();
    const buffer = await getBytes(at(`v1/results/${job.hash}`), ctl.signal, onGot);
    return { hash: job.hash, buffer, job };
  })();
  const cancel = async () => {
    cancelAsked = true;
    ctl.abort();
    // an upload under way: abort it (the server makes no job of a body cut short); once the
    // body is sent, the answer (at most Prefer's 2 s) names the job to DELETE
    // (a 200 answer coming, the result itself: abort its download)
    if (xhr) {
      if (!uploaded || xhr.answering()) xhr.abort();
      return;
    }
    if (loc && !canceled) await del();
  };
  return { done, cancel, jobUrl: () => loc };
}
