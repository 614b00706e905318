// page.js URL OUTDIR LONGJOB.json BIG.json — the browser checks of the page at / (run by
// tests/t_page.sh): headless Chromium (Debian's /usr/bin/chromium, driven by playwright-core)
// against a cellard started with --workers 1 --job-threads 1.  Every picture is checked
// against the result's own numbers, read from GET /v1/results/{hash} here (never against
// stored images): faces drawn = the result's faces (and the pixel where each face's number
// goes has that face's colour), meshes = cells, a Boolean's highlighted faces or cells = its
// "result" cells, shown by default as one region or one solid.  The traps a new user met
// (issue 28, item 5) each have a check: an op chosen before a file loads is kept, and a new op
// recomputes; numbers keep their exponents (a tiny and a huge volume); the counts are the
// result's stats; the explode label follows its slider; the pointer's place is said as such;
// upload, download and drawing progress, each with a Cancel that stops it (through a small
// proxy that slows the bytes down); face numbers that would overlap are left out.  Also the
// mesh files (STL, PLY, 3MF), the 3D download links, several GeoJSON files as a "layers"
// request, and the page served under a sub-path (/cellar/, through the proxy): every URL it
// uses is relative.  Prints "ok NAME" or "FAIL NAME: why" per check, "figure: ..." lines
// (page weight, time to the first picture), screenshots in OUTDIR, and "N passed, N failed"
// last.
'use strict';
const fs = require('fs');
const http = require('http');
const path = require('path');
const zlib = require('zlib');
const { chromium } = require('playwright-core');

const [base, outdir, longJob, bigJob] = process.argv.slice(2);
// the waits' bounds grow with this machine's measured pace (t_page.sh: CELLAR_PACE, its time for
// a reference job over a quiet machine's, at least 1)
const PACE = Math.max(1, Number(process.env.CELLAR_PACE) || 1);
const T = (ms) => Math.round(ms * PACE);
const url = base.replace(/\/$/, '');
let P = 0, F = 0;
const ok = (name) => { P++; console.log(`ok ${name}`); };
const fail = (name, why) => { F++; console.log(`FAIL ${name}${why ? `: ${why}` : ''}`); };
// runs fn; a string it returns (or an exception) fails the check
async function check(name, fn) {
  try {
    const r = await fn();
    if (typeof r === 'string') fail(name, r);
    else ok(name);
  } catch (e) {
    fail(name, String(e && e.message ? e.message : e).split('\n')[0]);
  }
}
const figure = (t) => console.log(`figure: ${t}`);

async function getJSON(p) {
  const r = await fetch(url + p, { headers: { Accept: 'application/json' } });
  if (!r.ok) throw new Error(`GET ${p}: ${r.status}`);
  return r.json();
}
const same = (a, b) => a.length === b.length && a.every((x, i) => x === b[i]);
const fmtList = (a) => (a.length > 12 ? `${a.slice(0, 12).join(',')}…(${a.length})` : a.join(','));

// ---- the page ---------------------------------------------------------------------------------

let page;
const errors = []; // uncaught exceptions and CSP violations in the page

// Waits for the run after `run0` to end (drawn, error or canceled); returns the state.
async function settle(run0, timeout = T(30000)) {
  await page.waitForFunction((r) => window.cellar.run > r && ['drawn', 'error', 'canceled'].includes(window.cellar.state),
    run0, { timeout, polling: 50 });
  return page.evaluate(() => window.cellar.state);
}
const runNow = () => page.evaluate(() => window.cellar.run);
// a slider moved by a user: its value, then an input event
const slide = (sel, v) => page.evaluate(([s, x]) => {
  const e = document.querySelector(s);
  e.value = String(x);
  e.dispatchEvent(new Event('input', { bubbles: true }));
}, [sel, v]);
async function files(list) { // [{name, text}] as if chosen in the file input
  const r0 = await runNow();
  await page.setInputFiles('#file', list.map((f) => ({ name: f.name, mimeType: 'application/octet-stream', buffer: Buffer.from(f.text) })));
  return r0;
}
const errorText = () => page.evaluate(() => (document.getElementById('error').hidden ? '' : document.getElementById('error').innerText));

// The drawn picture against the result (fetched here): 2D faces (and their pixels) or 3D
// meshes; a Boolean's highlight; the download links.  Returns the result.
async function verifyPicture(label, opts = {}) {
  const hash = await page.evaluate(() => window.cellar.hash);
  if (!/^[0-9a-f]{64}$/.test(hash)) throw new Error(`no result hash (${hash})`);
  const res = await getJSON(`/v1/results/${hash}`);
  const mode = await page.evaluate(() => document.querySelector('input[name="mode"]:checked').value);
  await verifyMode(res, opts);
  if (res.result) { // a Boolean: its other mode too (its cells, or the result as one), then back
    const other = mode === 'result' ? 'cells' : 'result';
    await page.check(`input[name="mode"][value="${other}"]`);
    await verifyMode(res, opts);
    await page.check(`input[name="mode"][value="${mode}"]`);
  }
  const links = await page.$$eval('#downloads a', (as) => as.map((a) => [a.dataset.format, a.getAttribute('href'), a.href]));
  const formats = res.dim === 2 ? ['json', 'svg', 'geojson', 'npz'] : ['json', 'obj', 'stl', 'off', '3mf', 'glb', 'npz'];
  const pageUrl = await page.evaluate(() => document.baseURI);
  const want = formats.map((f) => {
    const rel = f === 'json' ? `v1/results/${hash}` : `v1/results/${hash}?format=${f}`;
    return [f, rel, new URL(rel, pageUrl).href];
  });
  if (JSON.stringify(links) !== JSON.stringify(want)) throw new Error(`downloads ${JSON.stringify(links)}`);
  if (outdir) await page.screenshot({ path: path.join(outdir, `${label.replace(/[^A-Za-z0-9.]+/g, '_')}.png`) });
  return res;
}

// The picture in the view's current mode: 'result' (a Boolean's result as one region or one
// solid) or 'cells'.
async function verifyMode(res, { pixels = true } = {}) {
  const dim = res.dim;
  const mode = await page.evaluate((d) => document.getElementById(d === 2 ? 'view2d' : 'view3d').dataset.mode, dim);
  const want = await page.evaluate(() => document.querySelector('input[name="mode"]:checked').value);
  if (mode !== (res.result ? want : 'cells')) throw new Error(`the view's mode is ${mode}, the control says ${want} (a Boolean: ${!!res.result})`);
  // what the view was last told is on the screen after the next frames
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  if (dim === 2) {
    const d = await page.evaluate(() => ({ ...window.cellar.view.drawn, canvas: Number(document.querySelector('#view2d canvas').dataset.faces) }));
    const want = res.FV.length;
    if (d.faces !== want || d.canvas !== want || (res.stats && res.stats.F !== undefined && res.stats.F !== want))
      throw new Error(`${d.faces} faces drawn (canvas says ${d.canvas}), the result has ${want} (stats.F ${res.stats && res.stats.F})`);
    if (pixels && want <= 400) {
      // the pixel where each face's number goes has the face's colour (or grey outside a
      // Boolean's result): the faces are really on the canvas, each where it should be
      const bad = await page.evaluate(() => {
        const v = window.cellar.view, c = v.canvas, ctx = c.getContext('2d', { willReadFrequently: true });
        const probe = document.createElement('canvas').getContext('2d', { willReadFrequently: true });
        const rgb = (css) => { probe.fillStyle = css; probe.fillRect(0, 0, 1, 1); return [...probe.getImageData(0, 0, 1, 1).data]; };
        const out = [], d = v.dpr || 1;
        for (let f = 0; f < v.model.faces; f++) {
          const p = v.facePixel(f);
          if (p.x < 2 || p.y < 2 || p.x > c.clientWidth - 2 || p.y > c.clientHeight - 2) { out.push(`${f}: out of view`); continue; }
          const got = [...ctx.getImageData(Math.round(p.x * d), Math.round(p.y * d), 1, 1).data];
          const want = rgb(p.fill);
          if (Math.max(...[0, 1, 2].map((i) => Math.abs(got[i] - want[i]))) > 16) out.push(`${f}: rgb ${got.slice(0, 3)} for ${p.fill}`);
        }
        return out;
      });
      if (bad.length) throw new Error(`face pixels: ${bad.slice(0, 4).join('; ')}`);
    }
    if (res.result) {
      const sel = await page.evaluate(() => ({ ids: window.cellar.view.drawnSelected(), n: window.cellar.view.drawn.selected }));
      if (!same(sel.ids, res.result.cells) || sel.n !== res.result.cells.length)
        throw new Error(`highlighted faces ${fmtList(sel.ids)} (${sel.n}), the result's cells ${fmtList(res.result.cells)}`);
    }
  } else {
    const m = await page.evaluate(() => {
      const v = window.cellar.view;
      const meshes = v.meshes;
      return {
        n: meshes.length, cells: meshes.map((o) => o.userData.cell),
        lit: meshes.filter((o) => o.material.opacity === 1 && !o.material.transparent).map((o) => o.userData.cell),
        tris: meshes.map((o) => o.geometry.attributes.position.count / 3),
      };
    });
    if (m.n !== res.CF.length || (res.stats && res.stats.C !== undefined && res.stats.C !== m.n))
      throw new Error(`${m.n} meshes, the result has ${res.CF.length} cells (stats.C ${res.stats && res.stats.C})`);
    if (!same(m.cells, m.cells.map((_, i) => i))) throw new Error('the meshes are not cells 0..C-1');
    if (m.tris.some((t) => t < 4)) throw new Error('a cell with fewer than 4 triangles');
    if (mode === 'result') {
      // one solid: the only mesh shown, one colour, enclosing the result's volume
      const r = await page.evaluate(() => {
        const v = window.cellar.view, shown = [];
        v.scene.traverseVisible((o) => { if (o.isMesh) shown.push(o); });
        const rm = v.resultMesh, p = rm ? rm.geometry.attributes.position.array : [];
        let vol = 0;
        for (let i = 0; i < p.length; i += 9) {
          vol += (p[i] * (p[i + 4] * p[i + 8] - p[i + 5] * p[i + 7]) - p[i + 1] * (p[i + 3] * p[i + 8] - p[i + 5] * p[i + 6]) +
            p[i + 2] * (p[i + 3] * p[i + 7] - p[i + 4] * p[i + 6])) / 6;
        }
        return { shown: shown.length, isResult: shown.length === 1 && shown[0] === rm, vol, tris: p.length / 9 };
      });
      const ext = Math.max(...[0, 1, 2].map((k) => Math.max(...res.V.map((q) => q[k])) - Math.min(...res.V.map((q) => q[k]))));
      const wantVol = res.result.volume * (2 / ext) ** 3;
      if (!r.isResult) throw new Error(`result mode: ${r.shown} meshes shown, not the result as one solid`);
      if (!(Math.abs(r.vol - wantVol) <= 1e-4 * Math.max(wantVol, 1e-3))) throw new Error(`the result solid encloses ${r.vol}, the result's volume is ${wantVol} (scaled)`);
    } else if (res.result) {
      if (!same(m.lit, res.result.cells)) throw new Error(`highlighted cells ${fmtList(m.lit)}, the result's cells ${fmtList(res.result.cells)}`);
    } else if (m.lit.length !== m.n) throw new Error(`${m.n - m.lit.length} cells faint without an op`);
    if (pixels) {
      const drawn = await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => {
        const c = document.querySelector('#view3d canvas'), w = c.width, h = c.height;
        const gl = c.getContext('webgl2') || c.getContext('webgl');
        const px = new Uint8Array(w * h * 4);
        gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
        let n = 0;
        for (let i = 0; i < px.length; i += 4) if (Math.abs(px[i] - 247) + Math.abs(px[i + 1] - 247) + Math.abs(px[i + 2] - 244) > 30) n++;
        r(n / (w * h));
      }))));
      if (!(drawn > 0.01)) throw new Error(`only ${(100 * drawn).toFixed(2)}% of the 3D view is not background`);
    }
  }
}

const fmtMB = (n) => `${(n / 1048576).toFixed(1)} MB`;

// A proxy that mounts the daemon at target under /cellar/ (any other path: 404), as a
// front server would: the page must work there.  up and down (bytes a second, 0: as fast as
// it goes) slow the request bodies and the answers; aborted lists the exchanges the browser
// cut short ("METHOD PATH upload" or "... download"); log every answer's "STATUS METHOD PATH".
function startProxy(target) {
  const t = new URL(target);
  const px = { up: 0, down: 0, aborted: [], log: [] };
  const pace = (src, dst, rate, done) => {
    const t0 = Date.now();
    let n = 0;
    src.on('data', (c) => {
      const ok = dst.write(c);
      n += c.length;
      const r = rate();
      const due = r > 0 ? t0 + (n / r) * 1000 - Date.now() : 0;
      if (due > 0 || !ok) {
        src.pause();
        let waits = (due > 0 ? 1 : 0) + (ok ? 0 : 1);
        const go = () => { if (--waits === 0) src.resume(); };
        if (due > 0) setTimeout(go, due);
        if (!ok) dst.once('drain', go);
      }
    });
    src.on('end', () => { done(); dst.end(); });
  };
  px.server = http.createServer((req, res) => {
    const what = `${req.method} ${req.url}`;
    if (!req.url.startsWith('/cellar/')) {
      px.log.push(`404 ${what}`);
      res.writeHead(404, { 'Content-Type': 'text/plain' });
      res.end('not under /cellar/');
      return;
    }
    let sent = false;
    const up = http.request({ host: t.hostname, port: t.port, method: req.method, path: req.url.slice('/cellar'.length), headers: req.headers }, (ur) => {
      px.log.push(`${ur.statusCode} ${what}`);
      res.writeHead(ur.statusCode, ur.headers);
      pace(ur, res, () => px.down, () => {});
    });
    up.on('error', () => res.destroy());
    // (the connection closed before the answer went: cut short, while the body came or after)
    res.on('close', () => {
      if (res.writableFinished) return;
      px.aborted.push(`${what} ${sent ? 'download' : 'upload'}`);
      up.destroy();
    });
    pace(req, up, () => px.up, () => { sent = true; });
  });
  return new Promise((resolve) => px.server.listen(0, '127.0.0.1', () => {
    px.url = `http://127.0.0.1:${px.server.address().port}`;
    resolve(px);
  }));
}

function shoelace(V, c) {
  let a = 0;
  for (let i = 0; i < c.length; i++) {
    const p = V[c[i]], q = V[c[(i + 1) % c.length]];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return a / 2;
}

// ---- the checks -------------------------------------------------------------------------------

async function main() {
  const browser = await chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
  page = await context.newPage();
  page.on('pageerror', (e) => errors.push(`uncaught: ${e.message}`));
  page.on('console', (m) => { if (/Content Security Policy|Refused to/.test(m.text())) errors.push(`csp: ${m.text()}`); });

  // the page weight: everything a fresh browser fetches to show the page (no examples asked for)
  // (bytes on the wire: headers and the body as sent, gzipped when the server gzipped it)
  const weight = { bytes: 0, wire: 0, n: 0, list: [] };
  const onResponse = async (r) => {
    const u = new URL(r.url());
    if (u.pathname !== '/' && !u.pathname.startsWith('/assets/')) return;
    try {
      const b = await r.body();
      const sz = await r.request().sizes();
      weight.bytes += b.length;
      // (a worker's script: Chromium reports no sizes; its Content-Length is what was sent)
      const sent = sz.responseBodySize || Number(await r.headerValue('content-length')) || b.length;
      weight.wire += sent + sz.responseHeadersSize;
      weight.n++;
      weight.list.push(`${u.pathname.replace(/-[0-9a-f]{10}\./, '.')} ${b.length}/${sent}`);
    } catch { /* a redirect or nothing */ }
  };
  page.on('response', onResponse);
  await page.goto(`${url}/`);
  await page.waitForFunction(() => window.cellar && Number(document.getElementById('example').dataset.count) > 0, null, { polling: 20 });
  const ready = await page.evaluate(() => Math.round(performance.now()));
  await page.waitForLoadState('networkidle');
  const load = await page.evaluate(() => Math.round(performance.getEntriesByType('navigation')[0].loadEventEnd));
  page.off('response', onResponse);

  await check('the page and its assets are served (ETag, Cache-Control, 304, 404 problem)', async () => {
    const r = await fetch(`${url}/`);
    const html = await r.text();
    if (r.status !== 200 || !/^text\/html/.test(r.headers.get('content-type'))) return `GET /: ${r.status} ${r.headers.get('content-type')}`;
    if (!/<title>cellar/.test(html)) return 'no <title>cellar';
    if (r.headers.get('cache-control') !== 'no-cache' || !/^"[0-9a-f]{32}(-gz)?"$/.test(r.headers.get('etag') || '')) return `/: ${r.headers.get('cache-control')} ${r.headers.get('etag')}`;
    if (!/default-src 'self'/.test(r.headers.get('content-security-policy') || '')) return 'no Content-Security-Policy';
    const absolute = [...html.matchAll(/(?:src|href|action)\s*=\s*"(\/[^"]*)"/g)].map((m) => m[1]);
    if (absolute.length) return `index.html names absolute paths (the page may sit under a sub-path): ${absolute.join(' ')}`;
    const assets = [...html.matchAll(/(?:src|href)="(assets\/[^"]+)"/g)].map((m) => `/${m[1]}`);
    if (assets.length < 2) return `the page names ${assets.length} assets (relative: assets/...)`;
    for (const a of assets) {
      const x = await fetch(url + a);
      await x.arrayBuffer();
      if (x.status !== 200 || !/immutable/.test(x.headers.get('cache-control') || '')) return `${a}: ${x.status} ${x.headers.get('cache-control')}`;
      const y = await fetch(url + a, { headers: { 'If-None-Match': x.headers.get('etag') } });
      if (y.status !== 304) return `${a} with If-None-Match: ${y.status}`;
      // node's fetch takes gzip: the tag names the gzipped bytes; without gzip, another tag
      if (/gzip/.test(x.headers.get('content-encoding') || '')) {
        const raw = await fetch(url + a, { headers: { 'Accept-Encoding': 'identity' } });
        const body = Buffer.from(await raw.arrayBuffer());
        if (raw.headers.get('content-encoding') || raw.headers.get('etag') === x.headers.get('etag') || !/-gz"$/.test(x.headers.get('etag')))
          return `${a}: identity ${raw.headers.get('content-encoding')} ${raw.headers.get('etag')}, gzip ${x.headers.get('etag')}`;
        const z = await fetch(url + a, { headers: { 'Accept-Encoding': 'identity', 'If-None-Match': x.headers.get('etag') } });
        if (z.status !== 304 || body.length < 1024) return `${a}: the gzip tag without gzip: ${z.status}; ${body.length} bytes`;
      }
    }
    const n = await fetch(`${url}/assets/nothing-here.js`);
    const p = await n.json().catch(() => ({}));
    if (n.status !== 404 || !/problem\+json/.test(n.headers.get('content-type')) || !p.detail) return `unknown asset: ${n.status} ${n.headers.get('content-type')}`;
    const m = await fetch(`${url}/assets/${assets[0].slice(8)}`, { method: 'POST', body: 'x', headers: { 'Content-Type': 'text/plain' } });
    if (m.status !== 405) return `POST to an asset: ${m.status}`;
  });
  figure(`page weight: ${weight.wire} bytes transferred (headers and gzipped bodies) in ${weight.n} responses, ` +
    `${weight.bytes} bytes decoded (path decoded/sent: ${weight.list.join(', ')}); the load event at ${load} ms, the examples listed at ${ready} ms`);
  await check('the page goes gzipped to a browser: every text asset of 1 KiB or more, with its own ETag', async () => {
    if (!(weight.wire < weight.bytes / 2)) return `${weight.wire} bytes sent for ${weight.bytes}`;
  });

  // ---- every example --------------------------------------------------------------------------
  const examples = await page.$$eval('#example option', (os) => os.filter((o) => o.value !== '').map((o) => [o.value, o.textContent]));
  if (examples.length < 6) fail('the examples picker lists examples/', `${examples.length} entries`);
  for (const [value, name] of examples) {
    let res = null;
    await check(`example ${name} renders (faces or cells as the result has them)`, async () => {
      const r0 = await runNow();
      await page.selectOption('#example', value);
      const st = await settle(r0);
      if (st !== 'drawn') return `${st}: ${await errorText()}`;
      res = await verifyPicture(`example-${name}`);
    });
    if (res && res.result)
      ok(`example ${name}: the highlight is the result's ${res.result.cells.length} ${res.dim === 2 ? 'faces' : 'cells'}`);
  }

  // ---- 2D interaction (floorplan, polygons) ---------------------------------------------------
  const pick = async (name) => {
    const v = examples.find((e) => e[1] === name);
    const r0 = await runNow();
    await page.selectOption('#example', v[0]);
    return settle(r0);
  };
  await check('2D hover: face id, area and membership as in the result', async () => {
    if (await pick('polygons.json') !== 'drawn') return 'polygons.json did not draw';
    const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
    const box = await page.locator('#view2d canvas.over').boundingBox();
    for (let f = 0; f < res.FV.length; f++) {
      const p = await page.evaluate((g) => window.cellar.view.facePixel(g), f);
      await page.mouse.move(box.x + p.x, box.y + p.y);
      await page.waitForFunction((g) => document.getElementById('info').dataset.face === String(g), f, { timeout: T(3000), polling: 50 });
      const text = await page.textContent('#info');
      const area = Math.abs([res.FV[f], ...((res.holes || {})[f] || [])].reduce((a, c) => a + shoelace(res.V, c), 0));
      const m = /area ([0-9.e+-]+)/.exec(text);
      if (!m || Math.abs(Number(m[1]) - area) > 1e-5 * Math.max(1, area)) return `face ${f}: "${text}", area ${area}`;
      const mem = res.membership.indices.slice(res.membership.indptr[f], res.membership.indptr[f + 1]);
      const shown = /in ([^·]*?)(?: ·|$)/.exec(text.replace(/ at \(.*$/, ''));
      const ids = shown ? [...shown[1].matchAll(/(\d+) \(/g)].map((x) => Number(x[1])) : [];
      if (!same(ids, mem)) return `face ${f}: membership "${shown && shown[1]}", the result's ${mem}`;
      const inres = res.result.cells.includes(f);
      if (text.includes('not in the result') === inres) return `face ${f}: "${text}" (in the result: ${inres})`;
    }
    await page.mouse.move(box.x + 3, box.y + 3);
  });

  await check('2D zoom, pan and fit (wheel, drag, double-click)', async () => {
    if (await pick('floorplan.svg') !== 'drawn') return 'floorplan.svg did not draw';
    const box = await page.locator('#view2d canvas.over').boundingBox();
    const v0 = await page.evaluate(() => ({ k: window.cellar.view.k, tx: window.cellar.view.tx }));
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.wheel(0, -400);
    await page.waitForFunction((k) => window.cellar.view.k > k * 1.5, v0.k, { timeout: T(3000), polling: 50 });
    await page.mouse.down();
    await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 4 });
    await page.mouse.up();
    const v1 = await page.evaluate(() => ({ k: window.cellar.view.k, tx: window.cellar.view.tx }));
    await page.mouse.dblclick(box.x + box.width / 2, box.y + box.height / 2);
    const v2 = await page.evaluate(() => ({ k: window.cellar.view.k, tx: window.cellar.view.tx }));
    if (!(v1.k > v0.k * 1.5)) return `zoom: k ${v0.k} -> ${v1.k}`;
    if (Math.abs(v2.k - v0.k) > 1e-9 * v0.k || Math.abs(v2.tx - v0.tx) > 1e-6) return `fit: ${JSON.stringify(v0)} -> ${JSON.stringify(v2)}`;
    await verifyPicture('floorplan-refit');
  });

  await check('2D explode: every face still drawn, each at its moved place', async () => {
    await slide('#explode', 1.3);
    await page.waitForFunction(() => window.cellar.view.explode === 1.3, null, { timeout: T(5000), polling: 50 });
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    await verifyPicture('floorplan-exploded');
    await page.check('#fnum');
    await page.check('#vnum');
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    if (outdir) await page.screenshot({ path: path.join(outdir, 'floorplan-exploded-numbers.png') });
    await page.uncheck('#fnum');
    await page.uncheck('#vnum');
    await slide('#explode', 1);
    await page.waitForFunction(() => window.cellar.view.explode === 1, null, { timeout: T(5000), polling: 50 });
  });

  await check('2D numbers: the face numbers are drawn (the canvas changes only where they go)', async () => {
    const snap = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => {
      const c = window.cellar.view.canvas;
      r(Array.from(c.getContext('2d', { willReadFrequently: true }).getImageData(0, 0, c.width, c.height).data));
    }))));
    const a = await snap();
    await page.check('#fnum');
    const b = await snap();
    await page.uncheck('#fnum');
    let changed = 0;
    for (let i = 0; i < a.length; i += 4) if (a[i] !== b[i] || a[i + 1] !== b[i + 1] || a[i + 2] !== b[i + 2]) changed++;
    const faces = await page.evaluate(() => window.cellar.view.model.faces);
    // each number is a few digits of 12 px: some tens to some hundreds of pixels each
    if (changed < faces * 20 || changed > faces * 2000) return `${changed} pixels changed for ${faces} numbers`;
  });

  await check('the options\' controls reach the request: precision, keep_dangling (dangling edges drawn), normalize', async () => {
    if (await pick('floorplan.svg') !== 'drawn') return 'floorplan.svg did not draw';
    const r0 = await runNow();
    await page.fill('#precision', '0.25');
    await page.check('#keep_dangling');
    await page.click('#go');
    if (await settle(r0) !== 'drawn') return await errorText();
    let res = await verifyPicture('floorplan-dangling');
    if (res.stats.precision !== 0.25) return `stats.precision ${res.stats.precision}`;
    const used = new Set(res.FE.flat().map((e) => Math.abs(e) - 1));
    const dangling = res.EV.filter((_, e) => !used.has(e)).length;
    const drawn = await page.evaluate(() => window.cellar.view.drawn.dangling);
    if (!dangling || drawn !== dangling) return `${drawn} dangling edges drawn, the result has ${dangling}`;
    const r1 = await runNow();
    await page.fill('#precision', '');
    await page.uncheck('#keep_dangling');
    await page.check('#normalize');
    await page.click('#go');
    if (await settle(r1) !== 'drawn') return await errorText();
    res = await verifyPicture('floorplan-normalized');
    if (res.V.some((p) => p[0] < -1e-9 || p[0] > 1 + 1e-9 || p[1] < -1e-9 || p[1] > 1 + 1e-9)) return 'normalize: V outside the unit square';
    const sent = await page.evaluate(() => window.cellar.sent);
    if (!sent.options.normalize || sent.options.keep_dangling || 'precision' in sent.options) return `sent options ${JSON.stringify(sent.options)}`;
  });

  // ---- 3D: op controls, pick, show/hide, explode, numbers -------------------------------------
  const both = examples.find((e) => /\.obj \+/.test(e[1]));
  await check('3D Boolean from the op control: intersection of box.obj and pyramid.obj (volume 7/12)', async () => {
    if (!both) return 'no combined example';
    if (await pick(both[1]) !== 'drawn') return 'did not draw';
    const r0 = await runNow();
    await page.selectOption('#op', 'intersection');
    await page.click('#go');
    if (await settle(r0) !== 'drawn') return await errorText();
    const res = await verifyPicture('box-pyramid-intersection');
    if (!res.result || Math.abs(res.result.volume - 7 / 12) > 1e-9) return `volume ${res.result && res.result.volume}`;
  });
  await check('the page\'s glb download of that result, opened by three.js\'s GLTFLoader: a mesh node per cell, then the result\'s', async () => {
    const href = await page.$eval('#downloads a[data-format="glb"]', (a) => a.href);
    const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
    const r = await fetch(href);
    if (!r.ok || r.headers.get('content-type') !== 'model/gltf-binary') return `GET ${href}: ${r.status} ${r.headers.get('content-type')}`;
    const ab = await r.arrayBuffer();
    const loader = path.join(__dirname, '..', 'web', 'node_modules', 'three', 'examples', 'jsm', 'loaders', 'GLTFLoader.js');
    const { GLTFLoader } = await import(require('url').pathToFileURL(loader).href);
    const gltf = await new Promise((resolve, reject) => new GLTFLoader().parse(ab, '', resolve, reject));
    const nodes = gltf.scene.children;
    const want = [...res.CF.map((_, i) => `cell${i}`), 'result'];
    const names = nodes.map((n) => n.name);
    if (!same(names, want)) return `nodes ${fmtList(names)}, want ${fmtList(want)}`;
    const bad = nodes.filter((n) => !n.isMesh || !n.geometry.index || n.geometry.index.count < 12 || n.geometry.index.count % 3);
    if (bad.length) return `${bad.map((n) => n.name).join(', ')}: not meshes of triangles`;
    const tris = nodes[nodes.length - 1].geometry.index.count / 3;
    figure(`glb of the intersection: ${nodes.length} nodes (${res.CF.length} cells + result), the result ${tris} triangles, ${ab.byteLength} bytes`);
  });
  await check('3D Boolean from an expression: ["-", 0, 1] of box.obj and pyramid.obj (volume 89/12)', async () => {
    const r0 = await runNow();
    await page.selectOption('#op', 'expr');
    await page.fill('#expr', '["-", 0, 1]');
    await page.click('#go');
    if (await settle(r0) !== 'drawn') return await errorText();
    const res = await verifyPicture('box-pyramid-difference');
    if (!res.result || Math.abs(res.result.volume - 89 / 12) > 1e-9) return `volume ${res.result && res.result.volume}`;
    const text = await page.textContent('#counts');
    if (!text.includes(`${res.result.cells.length} cells`)) return `counts: ${text}`;
  });
  await check('3D pick: a click on a cell shows its id, volume and faces', async () => {
    const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
    const box = await page.locator('#view3d canvas').boundingBox();
    // the screen position of each cell's centre; click until a cell is picked
    const at = await page.evaluate(() => {
      const v = window.cellar.view;
      return v.meshes.map((m) => {
        const c = v.model.centre, i = m.userData.cell;
        const p = { x: c[3 * i], y: c[3 * i + 1], z: c[3 * i + 2] };
        const w = m.position.clone().set(p.x, p.y, p.z).add(m.position).project(v.camera);
        return [(w.x + 1) / 2, (1 - w.y) / 2];
      });
    });
    for (const [x, y] of at) {
      await page.mouse.click(box.x + x * box.width, box.y + y * box.height);
      const c = Number(await page.evaluate(() => document.getElementById('info').dataset.cell));
      if (c >= 0) {
        const text = await page.textContent('#info');
        const vol = /volume ([0-9.e+-]+)/.exec(text);
        const nf = /(\d+) faces/.exec(text);
        if (!vol || Math.abs(Number(vol[1]) - res.stats.volumes[c]) > 1e-5 * res.stats.volumes[c]) return `cell ${c}: "${text}", volume ${res.stats.volumes[c]}`;
        if (!nf || Number(nf[1]) !== res.CF[c].length) return `cell ${c}: "${text}", ${res.CF[c].length} faces`;
        return undefined;
      }
    }
    return 'no click picked a cell';
  });
  await check('3D show/hide: a cell\'s box hides its mesh, "result only", "show all"', async () => {
    const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
    await page.uncheck('#celllist input[data-cell="0"]');
    if (await page.evaluate(() => window.cellar.view.meshes[0].visible)) return 'cell 0 still visible';
    await page.click('#resultonly');
    const vis = await page.evaluate(() => window.cellar.view.meshes.filter((m) => m.visible).map((m) => m.userData.cell));
    if (!same(vis, res.result.cells)) return `result only: ${vis} visible, the result ${res.result.cells}`;
    await page.click('#showall');
    const all = await page.evaluate(() => window.cellar.view.meshes.every((m) => m.visible));
    if (!all) return 'show all left a cell hidden';
  });
  await check('3D explode and cell numbers', async () => {
    await slide('#explode', 2);
    await page.check('#cnum');
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    const st = await page.evaluate(() => ({
      moved: window.cellar.view.meshes.filter((m) => m.position.length() > 1e-6).length,
      labels: [...document.querySelectorAll('#view3d .labels3d span')].map((s) => s.textContent),
      cells: window.cellar.view.meshes.length,
    }));
    if (outdir) await page.screenshot({ path: path.join(outdir, 'box-pyramid-exploded-numbers.png') });
    await page.uncheck('#cnum');
    await slide('#explode', 1);
    if (st.moved < st.cells - 1) return `${st.moved} of ${st.cells} cells moved`;
    if (!same(st.labels, st.labels.map((_, i) => String(i))) || st.labels.length !== st.cells) return `labels ${st.labels}`;
  });

  // ---- inputs: GeoJSON, OFF, OBJ objects ------------------------------------------------------
  await check('GeoJSON: a FeatureCollection becomes a polygons request (union highlighted)', async () => {
    const fc = {
      type: 'FeatureCollection',
      features: [
        { type: 'Feature', properties: { name: 'A' }, geometry: { type: 'Polygon', coordinates: [[[0, 0], [4, 0], [4, 4], [0, 4], [0, 0]], [[1, 1], [1, 2], [2, 2], [2, 1], [1, 1]]] } },
        { type: 'Feature', properties: { name: 'B' }, geometry: { type: 'MultiPolygon', coordinates: [[[[3, 3], [6, 3], [6, 6], [3, 6], [3, 3]]], [[[8, 0], [9, 0], [9, 1], [8, 1], [8, 0]]]] } },
        { type: 'Feature', properties: { name: 'a point' }, geometry: { type: 'Point', coordinates: [5, 5] } },
      ],
    };
    if (await page.inputValue('#op') !== 'union') { // (the op chosen before is kept: union here)
      const r = await runNow();
      await page.selectOption('#op', 'union');
      await settle(r);
    }
    const r0 = await files([{ name: 'parcels.geojson', text: JSON.stringify(fc) }]);
    if (await settle(r0) !== 'drawn') return await errorText();
    const req = await page.textContent('#summary');
    if (!/2 polygons/.test(req) || !/1 feature without a polygon left out/.test(req)) return `summary "${req}"`;
    const res = await verifyPicture('geojson');
    if (!res.result || Math.abs(res.result.area - (16 - 1 + 9 - 1 + 1)) > 1e-9) return `union area ${res.result && res.result.area}`;
    // a face with a hole: the hover says the face has it, and where the pointer is, as such
    const f = await page.evaluate(() => window.cellar.view.model.nholes.findIndex((n) => n > 0));
    if (f < 0) return 'no face with a hole';
    const box = await page.locator('#view2d canvas.over').boundingBox();
    const p = await page.evaluate((g) => window.cellar.view.facePixel(g), f);
    await page.mouse.move(box.x + p.x, box.y + p.y);
    await page.waitForFunction((g) => document.getElementById('info').dataset.face === String(g), f, { timeout: T(3000), polling: 50 });
    const text = await page.textContent('#info');
    await page.mouse.move(box.x + 3, box.y + 3);
    if (!/the face has 1 hole/.test(text) || !/ · pointer at \(-?[\d.e+-]+, -?[\d.e+-]+\)$/.test(text) || /hole at/.test(text)) return `hover: "${text}"`;
  });
  await check('OFF and OBJ files together: a solid each', async () => {
    const off = 'OFF\n# a tetrahedron\n4 4 6\n0.5 0.5 0.5\n3 0.5 0.5\n0.5 3 0.5\n0.5 0.5 3\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n';
    const box = fs.readFileSync('examples/box.obj', 'utf8');
    const r0 = await files([{ name: 'tet.off', text: off }, { name: 'box.obj', text: box }]);
    if (await settle(r0) !== 'drawn') return await errorText();
    const s = await page.textContent('#summary');
    if (!/2 solids/.test(s)) return `summary "${s}"`;
    await verifyPicture('off-and-obj');
  });
  await check('an OBJ file with two objects ("o"): two solids', async () => {
    const tet = (d) => [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]].map((p) => `v ${p[0] + d} ${p[1] + d} ${p[2] + d}`).join('\n');
    const obj = `o first\n${tet(0)}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\no second\n${tet(0.25)}\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n`;
    const r0 = await files([{ name: 'two.obj', text: obj }]);
    if (await settle(r0) !== 'drawn') return await errorText();
    const s = await page.textContent('#summary');
    if (!/two\.obj:first, two\.obj:second: 2 solids/.test(s)) return `summary "${s}"`;
    await verifyPicture('obj-objects');
  });

  // ---- bad inputs: readable errors ------------------------------------------------------------
  const badCases = [
    ['a malformed SVG: the server\'s 422 with line and column', [{ name: 'broken.svg', text: '<svg xmlns="http://www.w3.org/2000/svg">\n<g>\n<line x1="0" y1="0" x2="1" y2="1"/>\n</svg>\n' }],
      (t) => /422/.test(t) && /line \d+, column \d+/.test(t)],
    ['an invalid request: the problem\'s detail and its JSON path, with the value there', [{ name: 'bad.json', text: '{"kind":"polygons","polygons":[[[[0,0],[2,0],[2,2]]],[[[1,1],[3,1],"x"]]],"op":"union"}' }],
      (t) => /422/.test(t) && /at polygons\[1\]\[0\]\[2\] = "x"/.test(t)],
    ['an OBJ with a bad face: the file and its line', [{ name: 'bad.obj', text: 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' }],
      (t) => /bad\.obj: line 4: vertex index 9 out of range/.test(t)],
    ['a .json that is not JSON', [{ name: 'notjson.json', text: '{"kind": "lines", ' }], (t) => /notjson\.json: not JSON/.test(t)],
    ['a file of another kind', [{ name: 'notes.txt', text: 'hello' }], (t) => /notes\.txt: not an SVG, OBJ, OFF, STL, PLY, 3MF, JSON or GeoJSON file/.test(t)],
    ['an op expression that is not valid for the inputs: the path in op', [{ name: 'op.json', text: '{"kind":"solids","solids":[{"V":[[0,0,0],[1,0,0],[0,1,0],[0,0,1]],"FV":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}],"op":["-",0,7]}' }],
      (t) => /422/.test(t) && /op\[2\]/.test(t)],
  ];
  for (const [name, input, test] of badCases) {
    await check(`a bad input shows a readable error: ${name}`, async () => {
      const r0 = await runNow();
      await page.setInputFiles('#file', input.map((f) => ({ name: f.name, mimeType: 'application/octet-stream', buffer: Buffer.from(f.text) })));
      await page.waitForFunction((r) => window.cellar.state === 'error' || (window.cellar.run > r && ['drawn', 'canceled'].includes(window.cellar.state)), r0, { timeout: T(15000), polling: 50 });
      const t = await errorText();
      if (!test(t)) return `the error says "${t.replace(/\n/g, ' | ')}"`;
      if (outdir && /SVG/.test(name)) await page.screenshot({ path: path.join(outdir, 'error-svg.png') });
      if (outdir && /JSON path/.test(name)) await page.screenshot({ path: path.join(outdir, 'error-path.png') });
    });
  }

  // ---- the figures: five cubes, 100 000 faces ---------------------------------------------------
  await check('five cubes (tests/data/mesh/fivecubes-input.json as five OBJ files): 26 cells, time to the first picture', async () => {
    const d = JSON.parse(fs.readFileSync('tests/data/mesh/fivecubes-input.json', 'utf8'));
    const list = [];
    for (let k = 0; k < 5; k++) {
      let t = '';
      for (let i = 0; i < 8; i++) t += `v ${d.V[8 * k + i].join(' ')}\n`;
      for (const q of d.FV.slice(6 * k, 6 * k + 6)) { // LAR cuboid order a b c d: the cycle a b d c
        const [a, b, c, e] = q.map((x) => x - 8 * k);
        t += `f ${a} ${b} ${e} ${c}\n`;
      }
      list.push({ name: `cube${k}.obj`, text: t });
    }
    const w0 = Date.now();
    const r0 = await files(list);
    if (await settle(r0) !== 'drawn') return await errorText();
    const wall = Date.now() - w0;
    const res = await verifyPicture('fivecubes');
    if (res.CF.length !== 26) return `${res.CF.length} cells (LAR.jl's arrangement has 26)`;
    const t = await page.evaluate(() => window.cellar.timing);
    figure(`five cubes: first picture ${Math.round(t.drawn)} ms after the files were given (result in ${Math.round(t.result)} ms, ` +
      `parsed and triangulated in ${Math.round(t.prepared - t.result)} ms, drawn in ${Math.round(t.drawn - t.prepared)} ms; ` +
      `${wall} ms as the test saw it); ${res.CF.length} cells, ${res.FV.length} faces`);
  });

  if (bigJob) {
    await check('100 000 faces: every face drawn, time to the first picture, the view stays usable', async () => {
      const w0 = Date.now();
      const r0 = await runNow();
      await page.setInputFiles('#file', bigJob);
      await page.evaluate(() => {
        window.__long = [];
        new PerformanceObserver((l) => { for (const e of l.getEntries()) window.__long.push(e.duration); }).observe({ entryTypes: ['longtask'] });
      });
      if (await settle(r0, 120000) !== 'drawn') return await errorText();
      const wall = Date.now() - w0;
      const res = await verifyPicture('lines-100k', { pixels: false });
      if (res.FV.length < 100000) return `only ${res.FV.length} faces: the test wants 100 000`;
      const t = await page.evaluate(() => ({ ...window.cellar.timing, long: window.__long, ms: window.cellar.view.model.ms }));
      // usable: a zoom step, a pan and a hover, each timed to the next painted frame
      const box = await page.locator('#view2d canvas.over').boundingBox();
      const frame = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
      let z = Date.now();
      await page.mouse.wheel(0, -300);
      await frame();
      const zoomMs = Date.now() - z;
      z = Date.now();
      await page.mouse.down();
      await page.mouse.move(box.x + box.width / 2 + 80, box.y + box.height / 2 + 30);
      await page.mouse.up();
      await frame();
      const panMs = Date.now() - z;
      z = Date.now();
      await page.mouse.move(box.x + box.width / 2 + 5, box.y + box.height / 2 + 5);
      await page.waitForFunction(() => Number(document.getElementById('info').dataset.face) >= 0, null, { timeout: T(5000), polling: 20 });
      const hoverMs = Date.now() - z;
      const hovered = Number(await page.evaluate(() => document.getElementById('info').dataset.face));
      if (!(hovered >= 0 && hovered < res.FV.length)) return `hover: face ${hovered}`;
      if (outdir) await page.screenshot({ path: path.join(outdir, 'lines-100k-zoomed.png') });
      const longest = Math.max(0, ...t.long);
      figure(`100 000 faces (${res.FV.length} faces, a ${(await page.evaluate(() => window.cellar.view.model.bytes)) / 1e6} MB result): first picture ` +
        `${Math.round(t.drawn)} ms after the file was given (result in ${Math.round(t.result)} ms, parsed in ${Math.round(t.ms.parse)} ms and ` +
        `prepared in ${Math.round(t.ms.prepare)} ms in the worker, drawn ${Math.round(t.drawn - t.prepared)} ms after; ${wall} ms as the test saw it); ` +
        `the page's thread: longest task ${Math.round(longest)} ms; a zoom step ${zoomMs} ms, a pan ${panMs} ms, a hover ${hoverMs} ms to the next frame`);
      if (longest > 2000) return `the page's thread was blocked ${Math.round(longest)} ms`;
    });
  }

  // ---- a long job: progress, then Cancel --------------------------------------------------------
  if (longJob) {
    await check('a long job shows increasing progress and the Cancel button cancels it', async () => {
      const r0 = await runNow();
      await page.setInputFiles('#file', longJob);
      const seen = [];
      const t0 = Date.now();
      let jobUrl = '';
      while (Date.now() - t0 < 60000) {
        const s = await page.evaluate(() => ({
          state: window.cellar.state, run: window.cellar.run, url: window.cellar.jobUrl, stage: window.cellar.stage,
          value: document.getElementById('progress').hidden ? -1 : document.getElementById('progress').position >= 0 ? document.getElementById('progress').value : -1,
          text: document.getElementById('status').textContent,
        }));
        if (s.run > r0 && s.state !== 'running') return `the job ended (${s.state}: ${s.text}) before it could be canceled`;
        if (s.url) jobUrl = s.url;
        if (s.stage === 'running' && s.value > 0 && (!seen.length || s.value !== seen[seen.length - 1])) seen.push(s.value);
        if (seen.length >= 2) break;
        await new Promise((r) => setTimeout(r, 100));
      }
      if (seen.length < 2 || !(seen[1] > seen[0])) return `progress seen: ${seen.join(', ')}`;
      if (outdir) await page.screenshot({ path: path.join(outdir, 'long-job-progress.png') });
      const status = await page.textContent('#status');
      await page.click('#cancel');
      if (await settle(r0, 20000) !== 'canceled') return `after Cancel: ${await page.evaluate(() => window.cellar.state)}: ${await errorText()}`;
      if (!jobUrl) return 'no job URL';
      if (!jobUrl.startsWith(`${url}/v1/jobs/`)) return `the job's URL ${jobUrl}: not under the page's`;
      const job = await getJSON(jobUrl.slice(url.length));
      if (job.state !== 'canceled') return `the job is ${job.state}`;
      const shown = await page.textContent('#status');
      if (!/canceled/.test(shown)) return `status "${shown}"`;
      figure(`long job: progress ${seen.map((x) => x.toFixed(2)).join(' -> ')} ("${status}"), then canceled (GET ${jobUrl}: ${job.state})`);
    });
  }

  // ---- face numbers of a large result: thinned where they would overlap ------------------------
  if (bigJob) {
    await check('face numbers of 100 000 faces: none overlaps another, the others left out and said so', async () => {
      const n = await page.evaluate(() => window.cellar.view.model && window.cellar.view.model.faces);
      if (!(n >= 100000)) return `the view holds ${n} faces (the 100 000 faces check did not draw)`;
      await page.click('#fit');
      await page.check('#fnum');
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      const st = await page.evaluate(() => ({
        placed: window.cellar.view.placed, labels: window.cellar.view.faceLabels.length,
        skipped: window.cellar.view.skipped, note: window.cellar.view.note.textContent,
      }));
      if (outdir) await page.screenshot({ path: path.join(outdir, 'lines-100k-numbers.png') });
      await page.uncheck('#fnum');
      if (!st.labels || st.placed.length !== st.labels) return `${st.labels} numbers drawn, ${st.placed.length} boxes`;
      for (let i = 0; i < st.placed.length; i++) {
        const a = st.placed[i];
        for (let j = i + 1; j < st.placed.length; j++) {
          const b = st.placed[j];
          if (a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]) return `numbers ${i} and ${j} overlap: ${a} ${b}`;
        }
      }
      if (!(st.skipped > 0) || !/overlap/.test(st.note)) return `${st.skipped} left out, the note "${st.note}"`;
      figure(`face numbers of ${n} faces at fit: ${st.labels} drawn, ${st.skipped} left out (they would overlap)`);
    });
  }

  // ---- several GeoJSON files: a "layers" request ---------------------------------------------------
  await check('several GeoJSON files: a "layers" request, a layer per file named by it, the op over the layers', async () => {
    const sq = (x, y, d) => ({ type: 'Polygon', coordinates: [[[x, y], [x + d, y], [x + d, y + d], [x, y + d], [x, y]]] });
    const parcels = {
      type: 'FeatureCollection',
      features: [
        { type: 'Feature', properties: { name: 'P1' }, geometry: sq(0, 0, 4) },
        { type: 'Feature', properties: { name: 'P2' }, geometry: sq(4, 0, 4) },
        { type: 'Feature', properties: { name: 'a point' }, geometry: { type: 'Point', coordinates: [1, 1] } },
      ],
    };
    const bodies = [];
    await context.route('**/v1/jobs', async (route) => {
      const r = route.request();
      if (r.method() === 'POST') bodies.push(r.postData());
      await route.continue();
    });
    try {
      await page.selectOption('#op', 'intersection');
      const r0 = await runNow();
      await page.setInputFiles('#file', [
        { name: 'parcels.geojson', mimeType: 'application/geo+json', buffer: Buffer.from(JSON.stringify(parcels)) },
        { name: 'zones.json', mimeType: 'application/json', buffer: Buffer.from(JSON.stringify(sq(2, 2, 4))) },
      ]);
      await page.waitForFunction((r) => window.cellar.run > r && ['drawn', 'error', 'canceled'].includes(window.cellar.state), r0, { timeout: T(15000), polling: 50 });
      if (!bodies.length) return 'no POST of v1/jobs seen';
      const req = JSON.parse(bodies[bodies.length - 1]);
      if (req.kind !== 'polygons' || 'polygons' in req) return `kind ${req.kind}, keys ${Object.keys(req)}`;
      if (JSON.stringify(Object.keys(req.layers)) !== '["parcels","zones"]') return `layers ${Object.keys(req.layers)}`;
      const p = req.layers.parcels, z = req.layers.zones;
      if (p.type !== 'FeatureCollection' || p.features.length !== 2 || p.features[1].properties.name !== 'P2') return `parcels ${JSON.stringify(p).slice(0, 200)}`;
      if (!Array.isArray(z) || z.length !== 1 || z[0].type !== 'Polygon') return `zones ${JSON.stringify(z).slice(0, 200)}`;
      if (req.op !== 'intersection') return `op ${JSON.stringify(req.op)} (intersection was chosen before the files)`;
      const summary = await page.textContent('#summary');
      if (!/2 layers: parcels \(2 polygons \(1 feature without a polygon left out\)\), zones \(1 polygons\)/.test(summary)) return `summary "${summary}"`;
      const ph = await page.getAttribute('#expr', 'placeholder');
      if (ph !== '["-","parcels",["+","zones"]]') return `the expression's placeholder ${ph}`;
      const r1 = await runNow();
      await page.selectOption('#op', 'expr');
      await page.fill('#expr', '["&", "parcels", "zones"]');
      await page.press('#expr', 'Enter');
      await page.waitForFunction((r) => window.cellar.run > r && ['drawn', 'error', 'canceled'].includes(window.cellar.state), r1, { timeout: T(15000), polling: 50 });
      const req2 = JSON.parse(bodies[bodies.length - 1]);
      if (JSON.stringify(req2.op) !== '["&","parcels","zones"]' || JSON.stringify(Object.keys(req2.layers)) !== '["parcels","zones"]') return `then: op ${JSON.stringify(req2.op)}, layers ${Object.keys(req2.layers)}`;
      figure(`layers: the page sent ${bodies.length} requests {"kind": "polygons", "layers": {"parcels": FeatureCollection(2), "zones": [Polygon]}, "op": ...}; the daemon of this branch answered: ${(await errorText()).replace(/\n/g, ' | ').slice(0, 160) || await page.evaluate(() => window.cellar.state)}`);
    } finally {
      await context.unroute('**/v1/jobs');
      await page.selectOption('#op', 'union');
    }
  });

  // ---- the page under a sub-path, through a proxy: relative URLs, and the traps ---------------
  const proxy = await startProxy(url);
  const main = page;
  const requests = [];
  page = await context.newPage();
  page.on('pageerror', (e) => errors.push(`uncaught (proxied page): ${e.message}`));
  page.on('request', (r) => requests.push(r.url()));
  const purl = `${proxy.url}/cellar/`;
  try {
    await page.goto(purl);
    await page.waitForFunction(() => window.cellar && Number(document.getElementById('example').dataset.count) > 0, null, { polling: 20, timeout: T(15000) });
    const ex = await page.$$eval('#example option', (os) => os.filter((o) => o.value !== '').map((o) => [o.value, o.textContent]));
    const pick = async (name) => {
      const v = ex.find((e) => e[1] === name);
      const r0 = await runNow();
      await page.selectOption('#example', v[0]);
      return settle(r0);
    };
    const boxObj = fs.readFileSync('examples/box.obj', 'utf8'), pyrObj = fs.readFileSync('examples/pyramid.obj', 'utf8');

    await check('an op chosen before a file is kept: intersection of two squares (GeoJSON) is 25, not their union', async () => {
      await page.selectOption('#op', 'intersection');
      const sq = (x, y) => ({ type: 'Feature', properties: {}, geometry: { type: 'Polygon', coordinates: [[[x, y], [x + 10, y], [x + 10, y + 10], [x, y + 10], [x, y]]] } });
      const r0 = await files([{ name: 'squares.geojson', text: JSON.stringify({ type: 'FeatureCollection', features: [sq(0, 0), sq(5, 5)] }) }]);
      if (await settle(r0) !== 'drawn') return await errorText();
      const res = await verifyPicture('op-kept-squares');
      const op = await page.inputValue('#op');
      const counts = await page.textContent('#counts');
      if (op !== 'intersection' || !res.result || res.result.area !== 25 || !/area 25\b/.test(counts)) return `op ${op}, area ${res.result && res.result.area}, "${counts}"`;
    });
    await check('a new op recomputes at once: difference of the two squares (75)', async () => {
      const r0 = await runNow();
      await page.selectOption('#op', 'difference');
      if (await settle(r0) !== 'drawn') return await errorText();
      const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
      if (!res.result || res.result.area !== 75) return `area ${res.result && res.result.area}`;
    });
    await check('difference chosen, then box.obj and pyramid.obj loaded: their difference (89/12), then union at once', async () => {
      const r0 = await files([{ name: 'box.obj', text: boxObj }, { name: 'pyramid.obj', text: pyrObj }]);
      if (await settle(r0) !== 'drawn') return await errorText();
      const res = await verifyPicture('op-kept-difference');
      if (!res.result || Math.abs(res.result.volume - 89 / 12) > 1e-9) return `volume ${res.result && res.result.volume}`;
      const counts = await page.textContent('#counts');
      if (!counts.includes('volume 7.41667')) return `counts "${counts}"`;
      const r1 = await runNow();
      await page.selectOption('#op', 'union');
      if (await settle(r1) !== 'drawn') return await errorText();
      const sent = await page.evaluate(() => window.cellar.sent.op);
      const u = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
      if (sent !== 'union' || !u.result || !(u.result.volume > 8)) return `union: sent ${sent}, volume ${u.result && u.result.volume}`;
    });

    // the meshes of box.obj and pyramid.obj in the other formats
    const readObj = (t) => {
      const V = [], T3 = [];
      for (const l of t.split('\n')) {
        const w = l.trim().split(/\s+/);
        if (w[0] === 'v') V.push(w.slice(1, 4).map(Number));
        if (w[0] === 'f') { const f = w.slice(1).map((x) => parseInt(x, 10) - 1); for (let i = 1; i + 1 < f.length; i++) T3.push([f[0], f[i], f[i + 1]]); }
      }
      return { V, T: T3 };
    };
    const box = readObj(boxObj), pyr = readObj(pyrObj);
    const stlBinary = (m) => {
      const b = Buffer.alloc(84 + 50 * m.T.length);
      b.write('binary STL from page.js', 0);
      b.writeUInt32LE(m.T.length, 80);
      m.T.forEach((t, i) => t.forEach((v, k) => m.V[v].forEach((x, j) => b.writeFloatLE(x, 84 + 50 * i + 12 + 12 * k + 4 * j))));
      return b;
    };
    const stlAscii = (m, name) => Buffer.from(`solid ${name}\n${m.T.map((t) => `facet normal 0 0 0\n outer loop\n${t.map((v) => `  vertex ${m.V[v].join(' ')}\n`).join('')} endloop\nendfacet\n`).join('')}endsolid ${name}\n`);
    const plyHeader = (m, fmt) => `ply\nformat ${fmt} 1.0\ncomment from page.js\nelement vertex ${m.V.length}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face ${m.T.length}\nproperty list uchar int vertex_indices\nend_header\n`;
    const plyAscii = (m) => Buffer.from(plyHeader(m, 'ascii') + m.V.map((p) => `${p.join(' ')} 200\n`).join('') + m.T.map((t) => `3 ${t.join(' ')}\n`).join(''));
    const plyBinary = (m) => {
      const h = Buffer.from(plyHeader(m, 'binary_little_endian'));
      const b = Buffer.alloc(13 * m.V.length + 13 * m.T.length);
      let o = 0;
      for (const p of m.V) { for (const x of p) { b.writeFloatLE(x, o); o += 4; } b.writeUInt8(200, o++); }
      for (const t of m.T) { b.writeUInt8(3, o++); for (const v of t) { b.writeInt32LE(v, o); o += 4; } }
      return Buffer.concat([h, b]);
    };
    const zip = (entries) => { // [name, Buffer, deflate?]
      const locals = [], central = [];
      let off = 0;
      for (const [name, data, deflate] of entries) {
        const body = deflate ? zlib.deflateRawSync(data) : data, n = Buffer.from(name);
        const crc = zlib.crc32 ? zlib.crc32(data) : 0;
        const lh = Buffer.alloc(30);
        lh.writeUInt32LE(0x04034b50, 0); lh.writeUInt16LE(20, 4); lh.writeUInt16LE(deflate ? 8 : 0, 8);
        lh.writeUInt32LE(crc >>> 0, 14); lh.writeUInt32LE(body.length, 18); lh.writeUInt32LE(data.length, 22); lh.writeUInt16LE(n.length, 26);
        const ch = Buffer.alloc(46);
        ch.writeUInt32LE(0x02014b50, 0); ch.writeUInt16LE(20, 4); ch.writeUInt16LE(20, 6); ch.writeUInt16LE(deflate ? 8 : 0, 10);
        ch.writeUInt32LE(crc >>> 0, 16); ch.writeUInt32LE(body.length, 20); ch.writeUInt32LE(data.length, 24); ch.writeUInt16LE(n.length, 28); ch.writeUInt32LE(off, 42);
        locals.push(lh, n, body);
        central.push(ch, n);
        off += 30 + n.length + body.length;
      }
      const cd = Buffer.concat(central), end = Buffer.alloc(22);
      end.writeUInt32LE(0x06054b50, 0); end.writeUInt16LE(entries.length, 8); end.writeUInt16LE(entries.length, 10);
      end.writeUInt32LE(cd.length, 12); end.writeUInt32LE(off, 16);
      return Buffer.concat([...locals, cd, end]);
    };
    const model3mf = (objs) => Buffer.from(`<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources>${
      objs.map(([name, m], i) => `<object id="${i + 1}" name="${name}" type="model"><mesh><vertices>${m.V.map((p) => `<vertex x="${p[0]}" y="${p[1]}" z="${p[2]}"/>`).join('')}</vertices><triangles>${
        m.T.map((t) => `<triangle v1="${t[0]}" v2="${t[1]}" v3="${t[2]}"/>`).join('')}</triangles></mesh></object>`).join('')}</resources><build>${objs.map((_, i) => `<item objectid="${i + 1}"/>`).join('')}</build></model>`);
    const threeMf = zip([['[Content_Types].xml', Buffer.from('<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"/>'), false],
      ['3D/3dmodel.model', model3mf([['box', box], ['pyramid', pyr]]), true]]);
    // the box placed by its build item moved by (10, 0, 0), the pyramid through an object of
    // components moved by (4, 0, 0) and its item by (6, 0, 0): the same pair, 10 to the right
    const moved3mf = Buffer.from(`<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources>${
      [['box', box], ['pyramid', pyr]].map(([name, m], i) => `<object id="${i + 1}" name="${name}" type="model"><mesh><vertices>${m.V.map((p) => `<vertex x="${p[0]}" y="${p[1]}" z="${p[2]}"/>`).join('')}</vertices><triangles>${
        m.T.map((t) => `<triangle v1="${t[0]}" v2="${t[1]}" v3="${t[2]}"/>`).join('')}</triangles></mesh></object>`).join('')
    }<object id="3" name="placed" type="model"><components><component objectid="2" transform="1 0 0 0 1 0 0 0 1 4 0 0"/></components></object></resources><build><item objectid="1" transform="1 0 0 0 1 0 0 0 1 10 0 0"/><item objectid="3" transform="1 0 0 0 1 0 0 0 1 6 0 0"/></build></model>`);
    const moved = zip([['3D/3dmodel.model', moved3mf, true]]);
    const meshCases = [
      ['a binary STL and an ASCII PLY', [{ name: 'box.stl', buffer: stlBinary(box) }, { name: 'pyramid.ply', buffer: plyAscii(pyr) }], /box\.stl, pyramid\.ply: 2 solids/],
      ['a binary PLY and an ASCII STL', [{ name: 'box.ply', buffer: plyBinary(box) }, { name: 'pyramid.stl', buffer: stlAscii(pyr, 'pyramid') }], /box\.ply, pyramid\.stl: 2 solids/],
      ['a 3MF file of two objects (deflated)', [{ name: 'both.3mf', buffer: threeMf }], /both\.3mf:box, both\.3mf:pyramid: 2 solids/],
      ['a 3MF file placing them by build items and components with transforms', [{ name: 'moved.3mf', buffer: moved }], /moved\.3mf:box, moved\.3mf:pyramid: 2 solids/, 10],
    ];
    await page.selectOption('#op', 'intersection');
    for (const [name, list, summaryRe, dx = 0] of meshCases) {
      await check(`mesh files: ${name}: the same solids as box.obj and pyramid.obj (welded), their intersection 7/12`, async () => {
        const r0 = await runNow();
        await page.setInputFiles('#file', list.map((f) => ({ name: f.name, mimeType: 'application/octet-stream', buffer: f.buffer })));
        if (await settle(r0) !== 'drawn') return await errorText();
        const s = await page.textContent('#summary');
        if (!summaryRe.test(s)) return `summary "${s}"`;
        const sent = await page.evaluate(() => window.cellar.sent);
        if (JSON.stringify(sent.solids) !== JSON.stringify([{ V: 8, FV: 12 }, { V: 5, FV: 6 }])) return `solids sent ${JSON.stringify(sent.solids)}`;
        const res = await verifyPicture(`mesh-${list.map((f) => f.name).join('-')}`);
        if (sent.op !== 'intersection' || !res.result || Math.abs(res.result.volume - 7 / 12) > 1e-9) return `op ${sent.op}, volume ${res.result && res.result.volume}`;
        const xmin = Math.min(...res.V.map((p) => p[0]));
        if (xmin !== dx) return `the solids begin at x = ${xmin}, not ${dx}`;
      });
    }

    await check('numbers keep their exponents: a tiny volume (1.46e-10) and a huge one (2.5e+20) as the page shows them', async () => {
      await page.selectOption('#op', 'union');
      const cube = (a, b, c) => `v 0 0 0\nv ${a} 0 0\nv ${a} ${b} 0\nv 0 ${b} 0\nv 0 0 ${c}\nv ${a} 0 ${c}\nv ${a} ${b} ${c}\nv 0 ${b} ${c}\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n`;
      for (const [name, dims, want] of [['tiny.obj', [0.000527, 0.000527, 0.000527], /^1\.46363e-10$/], ['huge.obj', [1e7, 1e7, 2.5e6], /^2\.5e\+20$/], ['big.obj', [1000, 1000, 25000], /^25000000000$/]]) {
        const r0 = await files([{ name, text: cube(...dims) }]);
        if (await settle(r0) !== 'drawn') return `${name}: ${await errorText()}`;
        const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
        const counts = await page.textContent('#counts');
        const m = /volume (\S+?)\.? /.exec(counts + ' ');
        const cell = await page.textContent('#celllist li');
        const c = /· (\S+)/.exec(cell);
        if (!m || !want.test(m[1]) || Math.abs(Number(m[1]) - res.result.volume) > 1e-5 * res.result.volume) return `${name}: counts "${counts}", volume ${res.result.volume}`;
        if (!c || !want.test(c[1])) return `${name}: the cell list says "${cell}"`;
        const box = await page.locator('#view3d canvas').boundingBox();
        await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
        const info = await page.textContent('#info');
        const v = /volume (\S+)/.exec(info);
        if (!v || !want.test(v[1])) return `${name}: the pick says "${info}"`;
      }
    });

    await check('the counts are the result\'s stats: the solids-op example (no EV in its fields) says its 64 edges', async () => {
      if (await pick('solids-op.json') !== 'drawn') return await errorText();
      const res = await getJSON(`/v1/results/${await page.evaluate(() => window.cellar.hash)}`);
      const st = res.stats, counts = await page.textContent('#counts');
      const want = `3D: ${st.V} vertices, ${st.E} edges, ${st.F} faces, ${st.C} cells`;
      if (!counts.startsWith(want) || st.E === 0) return `"${counts}", the stats say "${want}"`;
    });
    await check('the explode label follows its slider, also when a new input resets it', async () => {
      await page.selectOption('#op', 'intersection');
      await settle(await runNow() - 1);
      await slide('#explode', 2);
      const a = await page.textContent('#explodeval');
      if (await pick('box.obj + pyramid.obj') !== 'drawn') return await errorText();
      const b = await page.textContent('#explodeval'), v = await page.inputValue('#explode');
      if (a !== '2' || b !== '1' || v !== '1') return `slid to 2: "${a}"; after a new input: "${b}" (slider ${v})`;
    });
    await check('the result is shown as one solid by default, the cells a click away', async () => {
      const st = await page.evaluate(() => ({ mode: document.getElementById('view3d').dataset.mode, box: !document.getElementById('modebox').hidden }));
      if (st.mode !== 'result' || !st.box) return `mode ${st.mode}, the mode control shown: ${st.box}`;
      if (outdir) await page.screenshot({ path: path.join(outdir, 'result-as-one-solid.png') });
      await page.check('input[name="mode"][value="cells"]');
      const m2 = await page.evaluate(() => document.getElementById('view3d').dataset.mode);
      if (outdir) await page.screenshot({ path: path.join(outdir, 'result-cells.png') });
      await page.check('input[name="mode"][value="result"]');
      if (m2 !== 'cells') return `after a click on "its cells": ${m2}`;
    });

    // ---- progress and Cancel: upload, download, drawing ----------------------------------------
    const watch = async (r0, stage, until, limit = 30000) => { // samples cellar.progress of the run after r0 at stage
      const seen = [];
      const t0 = Date.now();
      while (Date.now() - t0 < T(limit)) {
        const s = await page.evaluate(() => ({ run: window.cellar.run, stage: window.cellar.stage, state: window.cellar.state, p: window.cellar.progress, text: document.getElementById('status').textContent, cancel: !document.getElementById('cancel').disabled, error: document.getElementById('error').innerText }));
        if (s.run <= r0) { await new Promise((r) => setTimeout(r, 15)); continue; }
        if (['drawn', 'error', 'canceled'].includes(s.state)) return { seen, end: s };
        if (s.stage === stage && s.p && (stage === 'drawing' || s.p.loaded !== undefined)) seen.push(s);
        if (until(seen)) return { seen };
        await new Promise((r) => setTimeout(r, 15));
      }
      return { seen, end: 'timeout' };
    };
    const canceled = async (r0) => {
      await page.click('#cancel');
      return settle(r0, T(15000));
    };
    await check('upload: progress as the request goes (slowed by the proxy), and Cancel aborts it', async () => {
      proxy.up = 3 << 20;
      proxy.aborted.length = 0;
      const pad = 'x'.repeat(24 << 20);
      const r0 = await files([{ name: 'big-upload.json', text: `{"kind":"lines","lines":[[[0,0],[1,1]]],"pad":"${pad}"}` }]);
      const w = await watch(r0, 'uploading', (s) => s.length > 2 && s[s.length - 1].p.loaded > s[0].p.loaded && s[s.length - 1].p.loaded > (4 << 20));
      const last = w.seen[w.seen.length - 1];
      if (w.end || !last) return `the upload was not seen going: ${JSON.stringify(w.end || w.seen.slice(-1))}`;
      if (!/sending the request: [\d.]+ MB of [\d.]+ MB \(\d+%\)/.test(last.text) || !last.cancel) return `status "${last.text}", Cancel enabled: ${last.cancel}`;
      if (outdir) await page.screenshot({ path: path.join(outdir, 'upload-progress.png') });
      const st = await canceled(r0);
      // (the proxy reads what the socket holds, at full speed now, before it sees the close)
      proxy.up = 0;
      for (let i = 0; i < 100 && !proxy.aborted.length; i++) await new Promise((r) => setTimeout(r, 100));
      if (st !== 'canceled') return `after Cancel: ${st}`;
      if (!proxy.aborted.some((a) => /^POST \/cellar\/v1\/jobs upload/.test(a))) return `the proxy saw no upload cut short: ${proxy.aborted}`;
      figure(`upload of ${fmtMB(last.p.total)}: ${fmtMB(last.p.loaded)} seen sent ("${last.text}"), then canceled: ${proxy.aborted.join(', ')}`);
    });
    if (bigJob) {
      await check('download: progress as the result comes (slowed by the proxy), and Cancel aborts it', async () => {
        proxy.down = 1 << 20;
        proxy.aborted.length = 0;
        const r0 = await runNow();
        await page.setInputFiles('#file', bigJob);
        const w = await watch(r0, 'downloading', (s) => s.length > 2 && s[s.length - 1].p.loaded > s[0].p.loaded, 120000);
        const last = w.seen[w.seen.length - 1];
        if (w.end || !last) return `the download was not seen going: ${JSON.stringify(w.end || w.seen.slice(-1))}`;
        if (!/receiving the result: [\d.]+ MB/.test(last.text) || !last.cancel) return `status "${last.text}", Cancel enabled: ${last.cancel}`;
        if (outdir) await page.screenshot({ path: path.join(outdir, 'download-progress.png') });
        const st = await canceled(r0);
        proxy.down = 0;
        for (let i = 0; i < 100 && !proxy.aborted.length; i++) await new Promise((r) => setTimeout(r, 100));
        if (st !== 'canceled') return `after Cancel: ${st}`;
        if (!proxy.aborted.some((a) => /download/.test(a))) return `the proxy saw no download cut short: ${proxy.aborted}`;
        figure(`download: ${fmtMB(last.p.loaded)} seen received ("${last.text}"), then canceled: ${proxy.aborted.join(', ')}`);
      });
      await check('drawing: progress as the worker prepares a large result, and Cancel stops it (the next run draws)', async () => {
        // Cancel is pressed at the first report of the drawing under way (a fraction in (0,
        // 1), Cancel enabled), from the report itself: the worker is not slowed by the CPU
        // throttling of the page, and a preparation of a third of a second on a fast machine
        // would end between a look from here and a click
        await page.evaluate(() => {
          const c = window.cellar;
          let p = c.progress;
          c.drawSeen = null;
          Object.defineProperty(c, 'progress', {
            configurable: true,
            get: () => p,
            set: (v) => {
              p = v;
              const b = document.getElementById('cancel');
              if (!c.drawSeen && v && c.stage === 'drawing' && v.fraction > 0 && v.fraction < 1 && !b.disabled) {
                c.drawSeen = { ...v, cancel: !b.disabled };
                b.click();
              }
            },
          });
        });
        let st, seen;
        const r0 = await runNow();
        try {
          await page.setInputFiles('#file', bigJob);
          st = await settle(r0, T(120000));
          seen = await page.evaluate(() => window.cellar.drawSeen);
        } finally {
          await page.evaluate(() => {
            const c = window.cellar, p = c.progress;
            delete c.progress;
            c.progress = p;
          });
        }
        if (!seen) return `the drawing was not seen going (the run ended ${st})`;
        if (st !== 'canceled') return `after Cancel at ${JSON.stringify(seen)}: ${st}`;
        const shown = await page.textContent('#status');
        if (!/canceled/.test(shown)) return `status "${shown}"`;
        figure(`drawing: canceled at ${seen.stage} ${seen.fraction.toFixed(2)}`);
        if (await pick('polygons.json') !== 'drawn') return `the next run: ${await errorText()}`;
      });
    }

    await check('under a sub-path (/cellar/ through a proxy): every request and every link of the page is relative to it', async () => {
      if (await pick('polygons.json') !== 'drawn') return await errorText();
      await verifyPicture('proxied-polygons');
      const outside = requests.filter((u) => !u.startsWith(purl) && !u.startsWith('data:'));
      if (outside.length) return `requests outside ${purl}: ${[...new Set(outside)].slice(0, 5).join(' ')}`;
      const kinds = ['assets/app-', 'assets/worker-', 'assets/examples-', 'assets/style-', 'v1/jobs'];
      for (const k of kinds) if (!requests.some((u) => u.startsWith(purl + k))) return `no request of ${purl}${k}`;
      const abs = await page.evaluate(() => [...document.querySelectorAll('[href], [src]')].map((e) => e.getAttribute('href') ?? e.getAttribute('src')).filter((u) => u.startsWith('/')));
      if (abs.length) return `absolute links in the page: ${abs.join(' ')}`;
      const notFound = proxy.log.filter((l) => l.startsWith('404'));
      if (notFound.length) return `the proxy refused: ${notFound.slice(0, 3).join(', ')}`;
      figure(`under /cellar/: ${requests.length} requests, all under ${purl}`);
    });
  } finally {
    await page.close();
    page = main;
    proxy.server.close();
  }

  await check('no uncaught error and no Content-Security-Policy violation in the page', async () => (errors.length ? errors.slice(0, 3).join(' | ') : undefined));
  await browser.close();
}

main().catch((e) => { fail('the browser checks ran', String(e && e.stack ? e.stack : e)); }).finally(() => {
  console.log(`${P} passed, ${F} failed`);
  process.exit(F ? 1 : 0);
});
