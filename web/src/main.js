// main.js — the page at /: an input (files dropped or chosen, or one of the repository's
// examples) becomes a request (input.js), the options' controls are applied to it, the job
// runs through the documented API off this thread (worker.js with api.js: progress, Cancel),
// where its result is also parsed and prepared, then it is drawn: 2D on a canvas
// (view2d.js), 3D in WebGL (view3d.js).  window.cellar exposes the state for the browser
// tests (tests/page.js).
import { Canceled, Problem } from './api.js';
import { fmt } from './format.js';
import { namesOf, requestFromFiles } from './input.js';
import { View2D } from './view2d.js';
import { View3D } from './view3d.js';

/* global __WORKER_URL__, __EXAMPLES_URL__ */
const $ = (id) => document.getElementById(id);
const REQUEST_SHOWN_MAX = 1 << 20; // a longer request is not put in the text area
const CELL_LIST_MAX = 500;
const NEEDS = {
  2: ['V', 'EV', 'FV', 'FE', 'holes', 'stats'],
  3: ['V', 'FV', 'holes', 'CF', 'CV', 'stats'],
};

const state = {
  input: null,     // {request, label, names}
  sent: null,      // the request last sent (an object)
  shown: null,     // the request for the text area
  job: null,       // the running job's {done, cancel}
  run: 0,          // runs started (a run's answers are dropped once a newer one starts)
  view: null,      // View2D or View3D
  model: null,
  t0: 0,
  opChosen: false, // the op control was set by the user (kept when a file loads)
  mode: 'result',  // a Boolean's picture: 'result' (one solid or region) or 'cells'
};
// stage: where a run is (uploading, running, downloading, drawing); progress: its last report
const cellar = { state: 'idle', run: 0, hash: '', jobUrl: '', timing: {}, model: null, view: null, stage: '', progress: null };
window.cellar = cellar;

function setState(s) {
  cellar.state = s;
  $('stage').dataset.state = s;
  // the picture on the stage is not of the current input until the next is drawn
  if (s !== 'drawn' && s !== 'idle') $('stage').classList.add('stale');
}

// ---- the worker -----------------------------------------------------------------------------
// It runs the jobs (network, polling, parsing, preparing: worker.js) and makes the exploded 2D
// paths; a request's answers come back by id.

let worker = null;
const pending = new Map(); // id -> {resolve, reject, onJob, onReceived, onProgress}
let wid = 0;

function problemOf(e) {
  if (e.canceled) return new Canceled();
  if (e.status) return new Problem(e.status, e);
  return new Error(e.message);
}

function theWorker() {
  if (worker) return worker;
  worker = new Worker(__WORKER_URL__, { type: 'module' });
  worker.onmessage = (ev) => {
    const d = ev.data, p = pending.get(d.id);
    if (!p) return;
    if (d.job) { if (p.onJob) p.onJob(d.job, d.url); return; }
    if (d.received) { if (p.onReceived) p.onReceived(d.received); return; }
    for (const k of ['sent', 'got', 'drawing']) if (d[k]) { if (p.onProgress) p.onProgress(k, d[k]); return; }
    if (d.cancelError) { showError(problemOf(d.cancelError)); return; }
    pending.delete(d.id);
    if (d.error) p.reject(problemOf(d.error));
    else p.resolve(d.model || d.paths);
  };
  worker.onerror = (ev) => {
    for (const p of pending.values()) p.reject(new Error(`the page's worker failed: ${ev.message || 'error'}`));
    pending.clear();
    worker = null;
  };
  return worker;
}

// Stops the worker where it is (a result being parsed or prepared hears no message): its
// requests end as canceled; the next request starts another.
function killWorker() {
  if (!worker) return;
  worker.terminate();
  worker = null;
  for (const p of pending.values()) p.reject(new Canceled());
  pending.clear();
}

function ask(msg, hooks) {
  const id = ++wid;
  const done = new Promise((resolve, reject) => {
    pending.set(id, { resolve, reject, ...hooks });
    theWorker().postMessage({ id, ...msg });
  });
  return { id, done };
}

// a job for body (JSON text), run by the worker at the service the page came from (its URLs
// made relative to the page's): {done (the prepared model), cancel}.  Cancel stops the
// upload, the job or the download (the worker, api.js), or, once the result is in and being
// prepared, the worker itself.
function runJob(body, flipY, hooks) {
  let preparing = false;
  const onReceived = (got) => { preparing = true; hooks.onReceived(got); };
  const { id, done } = ask({ run: { base: document.baseURI, body, flipY } }, { ...hooks, onReceived });
  return { done, cancel: () => (preparing ? killWorker() : theWorker().postMessage({ cancel: id })) };
}

// the 2D paths of the last result, exploded by k (made by the worker)
const explodePaths = (k) => ask({ explode: k }).done;

// ---- input ------------------------------------------------------------------------------

async function loadFiles(list) {
  state.t0 = performance.now();
  setState('loading');
  $('example').value = '';
  clearError();
  try {
    const files = await Promise.all([...list].map(async (f) => ({ name: f.name, bytes: new Uint8Array(await f.arrayBuffer()) })));
    setInput(await requestFromFiles(files));
  } catch (e) {
    showError(e);
    return;
  }
  compute();
}

async function loadExample(ex) {
  state.t0 = performance.now();
  setState('loading');
  clearError();
  try {
    const files = await Promise.all(ex.files.map(async (f) => {
      const r = await fetch(f.url);
      if (!r.ok) throw new Error(`${f.name}: ${r.status} ${r.statusText}`);
      return { name: f.name, bytes: new Uint8Array(await r.arrayBuffer()) };
    }));
    setInput(await requestFromFiles(files));
  } catch (e) {
    showError(e);
    return;
  }
  compute();
}

function setInput(inp) {
  state.input = inp;
  state.mode = 'result'; // a new input's Boolean: its result as one, first
  const req = inp.request, o = req.options || {};
  $('summary').textContent = `${inp.label} — a "${req.kind}" request`;
  $('precision').value = o.precision !== undefined ? String(o.precision) : '';
  $('keep_dangling').checked = !!o.keep_dangling;
  $('normalize').checked = !!o.normalize;
  $('y_up').checked = !!o.y_up;
  // the op: the file's own (a JSON request that names one), else the one the user chose (kept),
  // else the input's default (GeoJSON: union)
  if (req.op !== undefined && !inp.defaultOp) {
    $('op').value = typeof req.op === 'string' && OPS.includes(req.op) ? req.op : 'expr';
    $('expr').value = $('op').value === 'expr' ? JSON.stringify(req.op) : '';
    state.opChosen = false;
  } else if (!state.opChosen) {
    $('op').value = inp.defaultOp || '';
    $('expr').value = '';
  }
  const layers = req.layers && typeof req.layers === 'object' ? Object.keys(req.layers) : null;
  $('expr').placeholder = layers && layers.length >= 2
    ? JSON.stringify(['-', layers[0], ['+', ...layers.slice(1)]]) : '["-", 0, ["+", 1, 2]]';
  $('op').querySelector('option[value="difference"]').textContent = layers
    ? `difference (the first layer minus the others)` : 'difference (the first minus the others)';
  enableControls(req.kind);
  showRequest(req);
}
const OPS = ['union', 'intersection', 'difference', 'xor'];

function enableControls(kind) {
  const on = (id, yes) => { $(id).disabled = !yes; $(id).closest('label, .field').classList.toggle('off', !yes); };
  on('keep_dangling', ['lines', 'svg', 'polygons'].includes(kind));
  on('normalize', kind === 'svg');
  on('y_up', kind === 'svg');
  // (the op stays open: one chosen for the next file is kept; it is greyed where it does
  // not apply)
  on('op', true);
  $('op').closest('label').classList.toggle('off', kind !== 'polygons' && kind !== 'solids');
  $('op').querySelector('option[value=""]').disabled = kind === 'polygons';
  if (kind === 'polygons' && $('op').value === '') $('op').value = 'union';
  $('expr').hidden = $('op').value !== 'expr';
}

// The request in the text area: only while its box is open (a long text there costs the page
// a layout even when hidden).
function showRequest(req) {
  state.shown = req;
  if (!$('reqbox').open) {
    $('request').value = '';
    return;
  }
  const t = JSON.stringify(req);
  const ta = $('request');
  if (t.length <= REQUEST_SHOWN_MAX) {
    ta.value = JSON.stringify(req, null, t.length < 4000 ? 1 : 0);
    ta.disabled = false;
  } else {
    ta.value = `(${(t.length / 1048576).toFixed(1)} MB: too long to show here)`;
    ta.disabled = true;
  }
}

// The request to send: the input's, with the controls' options and op, and the fields the
// drawing needs when the request asks for fewer (reported in notes).
function buildRequest(notes) {
  const req = structuredClone(state.input.request);
  const kind = req.kind;
  const opts = req.options && typeof req.options === 'object' ? req.options : {};
  const p = $('precision').value.trim();
  if (p === '') delete opts.precision;
  else {
    const x = Number(p);
    if (!Number.isFinite(x) || x <= 0) throw new Error(`precision: "${p}" is not a positive number`);
    opts.precision = x;
  }
  const flag = (id, name) => {
    if ($(id).disabled) return;
    if ($(id).checked) opts[name] = true;
    else if (name in opts) opts[name] = false;
  };
  flag('keep_dangling', 'keep_dangling');
  flag('normalize', 'normalize');
  flag('y_up', 'y_up');
  if (kind === 'polygons' || kind === 'solids') {
    const op = $('op').value;
    if (op === 'expr') {
      try {
        req.op = JSON.parse($('expr').value);
      } catch (e) {
        throw new Error(`op expression: not JSON (${e.message}); for example ["-", 0, ["+", 1, 2]]`);
      }
    } else if (op) req.op = op;
    else delete req.op;
  }
  if (Array.isArray(opts.fields)) {
    // a Boolean's membership and result come only when named once fields are given
    const need = [...NEEDS[kind === 'solids' ? 3 : 2], ...(req.op ? ['membership', 'result'] : [])];
    const add = need.filter((f) => !opts.fields.includes(f));
    if (add.length) {
      opts.fields = [...opts.fields, ...add];
      notes.push(`options.fields: ${add.join(', ')} added for the drawing`);
    }
  }
  if (Object.keys(opts).length || req.options) req.options = opts;
  return req;
}

// ---- a run --------------------------------------------------------------------------------

async function compute() {
  if (!state.input) return;
  const run = ++state.run;
  cellar.run = run;
  if (!state.t0) state.t0 = performance.now();
  const t0 = state.t0;
  state.t0 = 0;
  clearError();
  if (state.job) state.job.cancel();
  const notes = [];
  let req;
  try {
    req = buildRequest(notes);
  } catch (e) {
    showError(e);
    return;
  }
  state.sent = req;
  cellar.sent = { kind: req.kind, options: req.options || {}, op: req.op };
  if (req.kind === 'solids' && Array.isArray(req.solids))
    cellar.sent.solids = req.solids.map((x) => ({ V: x && x.V ? x.V.length : 0, FV: x && x.FV ? x.FV.length : 0 }));
  if (req.layers) cellar.sent.layers = Object.keys(req.layers);
  showRequest(req);
  const body = JSON.stringify(req);
  cellar.timing = { t0, built: performance.now() - t0 };
  performance.mark('cellar:posted');
  cellar.hash = '';
  cellar.jobUrl = '';
  setState('running');
  $('resultbox').hidden = true;
  const bar = $('progress');
  bar.hidden = false;
  bar.removeAttribute('value');
  $('cancel').disabled = false;
  const secs = () => `${fmt((performance.now() - t0) / 1000, 2)} s`;
  // a stage's report: the status line, the bar (a fraction, or none: indeterminate)
  const report = (stage, text, fraction, extra = {}) => {
    cellar.stage = stage;
    cellar.progress = { stage, fraction, ...extra };
    if (fraction === undefined || fraction === null) bar.removeAttribute('value');
    else bar.value = Math.min(1, Math.max(0, fraction));
    status(`${text} · ${secs()}${notes.length ? ` (${notes.join('; ')})` : ''}`);
  };
  const amount = (loaded, total) => (total > 0
    ? `${mb(loaded)} of ${mb(total)} (${fmt(Math.floor((100 * loaded) / total))}%)` : mb(loaded));
  report('uploading', `sending the request (${mb(body.length)})`, 0);
  const flipY = !(req.kind === 'svg' && !(req.options && (req.options.y_up || req.options.normalize)));
  const job = runJob(body, flipY, {
    onJob: (j, url) => {
      if (run !== state.run) return;
      cellar.jobUrl = url || '';
      const pr = j.progress || {};
      const running = j.state === 'running';
      report('running', `${j.state}${running && pr.stage ? `: ${pr.stage}` : ''}${running ? ` ${fmt(Math.round(100 * (pr.fraction || 0)))}%` : ''}`,
        running || j.state === 'done' ? pr.fraction || 0 : null, { state: j.state });
    },
    onProgress: (kind, p) => {
      if (run !== state.run) return;
      if (kind === 'sent') report('uploading', `sending the request: ${amount(p.loaded, p.total)}`, p.total ? p.loaded / p.total : null, p);
      else if (kind === 'got' && (p.loaded > 65536 || cellar.stage === 'downloading'))
        report('downloading', `receiving the result: ${amount(p.loaded, p.total)}`, p.total ? p.loaded / p.total : null, p);
      else if (kind === 'drawing') report('drawing', `drawing: ${p.stage} ${fmt(Math.floor(100 * p.fraction))}%`, p.fraction, p);
    },
    onReceived: (got) => {
      if (run !== state.run) return;
      cellar.hash = got.hash;
      cellar.timing.result = performance.now() - t0;
      performance.mark('cellar:result');
      setState('drawing');
      report('drawing', `drawing (${mb(got.bytes)} of JSON)`, 0);
    },
  });
  state.job = job;
  let model;
  try {
    model = await job.done;
  } catch (e) {
    if (run !== state.run) return;
    state.job = null;
    $('cancel').disabled = true;
    bar.hidden = true;
    if (e instanceof Canceled) {
      setState('canceled');
      status('canceled');
    } else showError(e);
    return;
  }
  if (run !== state.run) return;
  state.job = null;
  $('cancel').disabled = true;
  cellar.timing.prepared = performance.now() - t0;
  performance.mark('cellar:prepared');
  try {
    await draw(model);
  } catch (e) {
    bar.hidden = true;
    showError(e);
    return;
  }
  $('stage').classList.remove('stale');
  // painted: after the next frame
  await new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));
  if (run !== state.run) return;
  bar.hidden = true;
  cellar.timing.drawn = performance.now() - t0;
  performance.mark('cellar:drawn');
  cellar.timing.parse = model.ms.parse;
  cellar.timing.prepare = model.ms.prepare;
  showResult(model, model.hash, model.bytes, notes);
  cellar.stage = '';
  status(`done in ${fmt(cellar.timing.drawn / 1000, 3)} s (result ${fmt(cellar.timing.result / 1000, 3)} s, picture ${fmt((cellar.timing.drawn - cellar.timing.result) / 1000, 3)} s)`);
  setState('drawn');
}

async function draw(model) {
  state.model = model;
  cellar.model = { dim: model.dim, faces: model.faces, cells: model.cells, result: model.result };
  $('placeholder').hidden = true;
  const is3 = model.dim === 3;
  $('view2d').hidden = is3;
  $('view3d').hidden = !is3;
  $('view2dopts').hidden = is3;
  $('view3dopts').hidden = !is3;
  $('explode').value = '1';
  syncLabels();
  $('modebox').hidden = !model.result;
  $('modebox').querySelector('.dimword').textContent = is3 ? 'solid' : 'region';
  for (const r of document.querySelectorAll('input[name="mode"]')) r.checked = r.value === state.mode;
  $('info').textContent = is3 ? 'Click a cell to pick it.' : 'Hover a face.';
  delete $('info').dataset.face;
  delete $('info').dataset.cell;
  if (state.view && (state.view instanceof View2D) === is3) {
    state.view.destroy();
    state.view = null;
  }
  if (is3) {
    if (!state.view) {
      try {
        state.view = new View3D($('view3d'), { onPick: pick3 });
      } catch (e) {
        throw new Error(`no 3D view: this browser gives no WebGL context (${e.message})`);
      }
    }
    state.view.show(model, state.mode);
    state.view.setLabels($('cnum').checked);
    cellList(model);
  } else {
    if (!state.view) state.view = new View2D($('view2d'), { onHover: hover2, explodePaths });
    state.view.show(model, state.mode);
    state.view.setNumbers({ faces: $('fnum').checked, vertices: $('vnum').checked });
    performance.mark('cellar:shown');
  }
  cellar.view = state.view;
}

// ---- what the page says -------------------------------------------------------------------

function status(t) {
  $('status').textContent = t;
}

function clearError() {
  const e = $('error');
  e.hidden = true;
  e.textContent = '';
}

// The value at a problem's JSON path ("solids[0].FV[4]", "polygons[1][0][2]") of the request
// sent, shortened, or undefined.
function valueAt(req, path) {
  let v = req;
  for (const m of path.matchAll(/([^.[\]]+)|\[(\d+)\]/g)) {
    if (v === null || typeof v !== 'object') return undefined;
    v = v[m[2] !== undefined ? Number(m[2]) : m[1]];
  }
  return v;
}

function showError(e) {
  setState('error');
  status('');
  $('progress').hidden = true;
  $('cancel').disabled = true;
  const box = $('error');
  box.textContent = '';
  const head = document.createElement('strong');
  const p = document.createElement('p');
  if (e instanceof Problem) {
    head.textContent = `${e.status} ${e.title || 'Error'}`;
    p.textContent = e.detail || e.message;
    box.append(head, p);
    if (e.path) {
      const w = document.createElement('p');
      w.className = 'path';
      w.append('at ');
      const c = document.createElement('code');
      c.textContent = e.path;
      w.append(c);
      const v = state.sent ? valueAt(state.sent, e.path) : undefined;
      if (v !== undefined) {
        const s = JSON.stringify(v);
        w.append(' = ');
        const cv = document.createElement('code');
        cv.textContent = s.length > 160 ? `${s.slice(0, 160)}…` : s;
        w.append(cv);
      }
      box.append(w);
    }
  } else {
    head.textContent = 'Error';
    p.textContent = e && e.message ? e.message : String(e);
    box.append(head, p);
  }
  box.hidden = false;
}

const mb = (n) => `${fmt(n / 1048576, 3)} MB`;

// The labels that show a control's value, from the controls (after any change of either).
function syncLabels() {
  $('explodeval').textContent = fmt(Number($('explode').value), 3);
}

function showResult(model, hash, size, notes) {
  $('resultbox').hidden = false;
  const s = model.stats || {};
  // the counts are the result's stats (what it counts, whatever fields it carries), else what
  // it carries
  const n = (k, have) => fmt(typeof s[k] === 'number' ? s[k] : have);
  const ms = s.ms && s.ms.total !== undefined ? ` · ${fmt(s.ms.total)} ms` : '';
  let t = model.dim === 3
    ? `3D: ${n('V', model.vertices)} vertices, ${n('E', model.edges)} edges, ${n('F', model.faces)} faces, ${n('C', model.cells)} cells${ms}`
    : `2D: ${n('V', model.vertices)} vertices, ${n('E', model.edges)} edges, ${n('F', model.faces)} faces${s.components !== undefined ? `, ${fmt(s.components)} components` : ''}${ms}`;
  if (model.result) {
    t += model.dim === 3
      ? `. Result: ${fmt(model.result.cells)} cells, volume ${fmt(model.result.volume)}`
      : `. Result: ${fmt(model.result.cells)} faces in ${fmt(model.result.polygons)} polygons, area ${fmt(model.result.area)}`;
  }
  if (model.layers) t += `. Layers: ${model.layers.map((l) => `${l.name} (${fmt(l.count)} features)`).join(', ')}`;
  $('counts').textContent = `${t}. ${fmt(size / 1024, size < 10240 ? 2 : 3)} KiB of JSON.`;
  const warn = [...(s.warnings || []), ...((s.svg && s.svg.warnings) || []), ...notes]
    .map((w) => (typeof w === 'string' ? w : w.message || JSON.stringify(w)));
  const wl = $('warnings');
  wl.textContent = '';
  for (const w of warn.slice(0, 8)) {
    const li = document.createElement('li');
    li.textContent = w;
    wl.append(li);
  }
  if (warn.length > 8) wl.append(Object.assign(document.createElement('li'), { textContent: `and ${warn.length - 8} more` }));
  const dl = $('downloads');
  dl.textContent = 'Download: ';
  // (relative to the page: the service may sit under a sub-path)
  const base = `v1/results/${hash}`, name = `cellar-${hash.slice(0, 12)}`;
  const links = [['JSON', base, 'json']];
  if (model.dim === 2) links.push(['SVG', `${base}?format=svg`, 'svg'], ['GeoJSON', `${base}?format=geojson`, 'geojson']);
  else {
    for (const [label, f] of [['OBJ', 'obj'], ['STL', 'stl'], ['OFF', 'off'], ['3MF', '3mf'], ['glTF (GLB)', 'glb']])
      links.push([label, `${base}?format=${f}`, f]);
  }
  links.push(['NPZ', `${base}?format=npz`, 'npz']);
  links.forEach(([label, href, ext], i) => {
    const a = document.createElement('a');
    a.href = href;
    a.download = `${name}.${ext}`;
    a.textContent = label;
    a.dataset.format = ext;
    if (i) dl.append(' · ');
    dl.append(a);
  });
}

function memberOf(model, i) {
  const m = model.membership;
  if (!m || i + 1 >= m.indptr.length) return null;
  const out = [];
  for (let k = m.indptr[i]; k < m.indptr[i + 1]; k++) out.push(m.indices[k]);
  return out;
}

function named(list) {
  const names = state.input ? state.input.names : [];
  return list.map((k) => (names[k] ? `${k} (${names[k]})` : String(k))).join(', ') || 'none';
}

function hover2(f, at) {
  const m = state.model;
  const info = $('info');
  // (the pointer's place, said as such: "1 hole at (x, y)" read as the hole's)
  const where = at ? `pointer at (${fmt(at[0])}, ${fmt(at[1])})` : '';
  if (!m || f < 0) {
    info.textContent = where ? `no face · ${where}` : 'Hover a face.';
    delete info.dataset.face;
    return;
  }
  let t = `face ${f} · area ${fmt(m.area[f])}${m.nholes[f] ? ` · the face has ${fmt(m.nholes[f])} hole${m.nholes[f] > 1 ? 's' : ''}` : ''}`;
  const mem = memberOf(m, f);
  if (mem) t += ` · in ${named(mem)}`;
  if (m.result) t += m.sel[f] ? ' · in the result' : ' · not in the result';
  info.textContent = `${t} · ${where}`;
  info.dataset.face = String(f);
}

function pick3(c) {
  const m = state.model;
  const info = $('info');
  info.textContent = '';
  info.dataset.cell = String(c);
  if (!m || c < 0) { info.textContent = 'Click a cell to pick it.'; return; }
  const faces = m.cf[c].split(' ');
  let t = `cell ${c} · volume ${m.volumes ? fmt(m.volumes[c]) : '?'} · ${fmt(faces.length)} faces: ${faces.slice(0, 24).map((x) => (x > 0 ? `+${x - 1}` : `−${-x - 1}`)).join(' ')}${faces.length > 24 ? ' …' : ''}`;
  const mem = memberOf(m, c);
  if (mem) t += ` · in ${named(mem)}`;
  if (m.result) t += m.sel[c] ? ' · in the result' : ' · not in the result';
  const p = document.createElement('span');
  p.textContent = t + ' ';
  const hide = document.createElement('button');
  hide.textContent = 'hide it';
  hide.onclick = () => setCellVisible(c, false);
  info.append(p, hide);
}

function setCellVisible(c, on) {
  state.view.setVisible(c, on);
  const box = document.querySelector(`#celllist input[data-cell="${c}"]`);
  if (box) box.checked = on;
}

function cellList(model) {
  const ul = $('celllist');
  ul.textContent = '';
  if (model.cells > CELL_LIST_MAX) {
    ul.append(Object.assign(document.createElement('li'), { textContent: `${fmt(model.cells)} cells: too many to list (pick one to hide it)` }));
    return;
  }
  for (let c = 0; c < model.cells; c++) {
    const li = document.createElement('li');
    const l = document.createElement('label');
    const b = document.createElement('input');
    b.type = 'checkbox';
    b.checked = true;
    b.dataset.cell = String(c);
    b.onchange = () => state.view.setVisible(c, b.checked);
    const sw = document.createElement('i');
    sw.className = model.result && !model.sel[c] ? 'swatch faint' : 'swatch';
    sw.style.background = `hsl(${((c * 137.508) % 360).toFixed(1)} 55% 60%)`;
    l.append(b, sw, ` ${c}${model.volumes ? ` · ${fmt(model.volumes[c])}` : ''}${model.result && model.sel[c] ? ' · result' : ''}`);
    li.append(l);
    ul.append(li);
  }
}

// ---- wiring -------------------------------------------------------------------------------

function wire() {
  const drop = $('drop');
  // (the input emptied once read: the same file chosen again is another change)
  $('file').addEventListener('change', () => {
    const list = [...$('file').files];
    $('file').value = '';
    if (list.length) loadFiles(list);
  });
  for (const t of ['dragenter', 'dragover']) drop.addEventListener(t, (e) => { e.preventDefault(); drop.classList.add('over'); });
  for (const t of ['dragleave', 'drop']) drop.addEventListener(t, () => drop.classList.remove('over'));
  drop.addEventListener('drop', (e) => { e.preventDefault(); if (e.dataTransfer.files.length) loadFiles(e.dataTransfer.files); });
  // a drop anywhere on the page is an input too (not the browser opening the file)
  document.addEventListener('dragover', (e) => e.preventDefault());
  document.addEventListener('drop', (e) => { e.preventDefault(); if (e.dataTransfer.files.length) loadFiles(e.dataTransfer.files); });
  $('example').addEventListener('change', () => {
    const ex = examples[Number($('example').value)];
    if (ex) loadExample(ex);
  });
  // an op chosen is the user's (kept when a file loads) and recomputes the result at once (an
  // expression: at Enter in its field)
  $('op').addEventListener('change', () => {
    state.opChosen = true;
    $('expr').hidden = $('op').value !== 'expr';
    if ($('op').value === 'expr') $('expr').focus();
    else if (state.input && ['polygons', 'solids'].includes(state.input.request.kind)) compute();
  });
  $('expr').addEventListener('change', () => { state.opChosen = true; });
  for (const r of document.querySelectorAll('input[name="mode"]')) {
    r.addEventListener('change', () => {
      if (!r.checked) return;
      state.mode = r.value;
      if (state.view && state.view.setMode) state.view.setMode(state.mode);
    });
  }
  $('expr').addEventListener('keydown', (e) => { if (e.key === 'Enter') compute(); });
  $('precision').addEventListener('keydown', (e) => { if (e.key === 'Enter') compute(); });
  $('go').addEventListener('click', () => compute());
  $('reqbox').addEventListener('toggle', () => {
    if ($('reqbox').open && state.shown && !$('request').value) showRequest(state.shown);
  });
  $('cancel').addEventListener('click', async () => {
    if (!state.job) return;
    $('cancel').disabled = true;
    status('canceling…');
    state.job.cancel();
  });
  $('apply').addEventListener('click', () => {
    let req;
    try {
      req = JSON.parse($('request').value);
    } catch (e) {
      showError(new Error(`the request is not JSON: ${e.message}`));
      return;
    }
    if (!req || typeof req !== 'object' || typeof req.kind !== 'string') {
      showError(new Error('the request is a JSON object with a "kind" (lines, svg, polygons, solids)'));
      return;
    }
    setInput({ request: req, label: 'the edited request', names: namesOf(req) });
    compute();
  });
  $('explode').addEventListener('input', () => {
    syncLabels();
    if (state.view) state.view.setExplode(Number($('explode').value));
  });
  const nums = () => state.view && state.view.setNumbers && state.view.setNumbers({ faces: $('fnum').checked, vertices: $('vnum').checked });
  $('fnum').addEventListener('change', nums);
  $('vnum').addEventListener('change', nums);
  $('fit').addEventListener('click', () => state.view && state.view.fit && state.view.fit());
  $('zoomin').addEventListener('click', () => state.view && state.view.zoom && state.view.zoom(2));
  $('zoomout').addEventListener('click', () => state.view && state.view.zoom && state.view.zoom(0.5));
  $('cnum').addEventListener('change', () => state.view && state.view.setLabels && state.view.setLabels($('cnum').checked));
  // (both show the cells)
  const cellsMode = () => {
    if (state.mode === 'cells') return;
    state.mode = 'cells';
    document.querySelector('input[name="mode"][value="cells"]').checked = true;
    state.view.setMode('cells');
  };
  $('showall').addEventListener('click', () => {
    const m = state.model;
    if (!m || m.dim !== 3) return;
    cellsMode();
    for (let c = 0; c < m.cells; c++) setCellVisible(c, true);
  });
  $('resultonly').addEventListener('click', () => {
    const m = state.model;
    if (!m || m.dim !== 3 || !m.result) return;
    cellsMode();
    for (let c = 0; c < m.cells; c++) setCellVisible(c, !!m.sel[c]);
  });
}

let examples = [];
async function loadExamples() {
  try {
    const r = await fetch(__EXAMPLES_URL__);
    examples = await r.json();
  } catch {
    examples = [];
  }
  const sel = $('example');
  examples.forEach((ex, i) => {
    const o = document.createElement('option');
    o.value = String(i);
    o.textContent = ex.name;
    sel.append(o);
  });
  sel.dataset.count = String(examples.length);
}

wire();
syncLabels();
loadExamples();
theWorker(); // loaded with the page, not at the first result
setState('idle');
