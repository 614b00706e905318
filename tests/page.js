// page.js URL OUTDIR LONGJOB.json BIG.json — the browser checks of the page at / (run by
// tests/t_page.sh): headless Chromium (Debian's /usr/bin/chromium, driven by playwright-core)
// against a cellard started with --workers 1 --job-threads 1.  Every picture is checked
// against the result's own numbers, read from GET /v1/results/{hash} here (never against
// stored images): faces drawn = the result's faces (and the pixel where each face's number
// goes has that face's colour), meshes = cells, a Boolean's highlighted faces or cells = its
// "result" cells.  Prints "ok NAME" or "FAIL NAME: why" per check, "figure: ..." lines (page
// weight, time to the first picture), screenshots in OUTDIR, and "N passed, N failed" last.
'use strict';
const fs = require('fs');
const path = require('path');
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
async function verifyPicture(label, { pixels = true } = {}) {
  const hash = await page.evaluate(() => window.cellar.hash);
  if (!/^[0-9a-f]{64}$/.test(hash)) throw new Error(`no result hash (${hash})`);
  const res = await getJSON(`/v1/results/${hash}`);
  const dim = res.dim;
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
      const meshes = v.scene.children.filter((o) => o.isMesh && o.userData.cell !== undefined);
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
    if (res.result) {
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
  const links = await page.$$eval('#downloads a', (as) => as.map((a) => [a.dataset.format, a.getAttribute('href')]));
  const want = dim === 2
    ? [['json', `/v1/results/${hash}`], ['svg', `/v1/results/${hash}?format=svg`], ['geojson', `/v1/results/${hash}?format=geojson`],
      ['npz', `/v1/results/${hash}?format=npz`]]
    : [['json', `/v1/results/${hash}`], ['obj', `/v1/results/${hash}?format=obj`], ['npz', `/v1/results/${hash}?format=npz`]];
  if (JSON.stringify(links) !== JSON.stringify(want)) throw new Error(`downloads ${JSON.stringify(links)}`);
  if (outdir) await page.screenshot({ path: path.join(outdir, `${label.replace(/[^A-Za-z0-9.]+/g, '_')}.png`) });
  return res;
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
    const assets = [...html.matchAll(/(?:src|href)="(\/assets\/[^"]+)"/g)].map((m) => m[1]);
    if (assets.length < 2) return `the page names ${assets.length} assets`;
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
  const both = examples.find((e) => /\+/.test(e[1]));
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
    const r0 = await files([{ name: 'parcels.geojson', text: JSON.stringify(fc) }]);
    if (await settle(r0) !== 'drawn') return await errorText();
    const req = await page.textContent('#summary');
    if (!/2 polygons/.test(req) || !/1 feature without a polygon left out/.test(req)) return `summary "${req}"`;
    const res = await verifyPicture('geojson');
    if (!res.result || Math.abs(res.result.area - (16 - 1 + 9 - 1 + 1)) > 1e-9) return `union area ${res.result && res.result.area}`;
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
    ['a file of another kind', [{ name: 'notes.txt', text: 'hello' }], (t) => /notes\.txt: not an SVG, OBJ, OFF, JSON or GeoJSON file/.test(t)],
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
          state: window.cellar.state, run: window.cellar.run, url: window.cellar.jobUrl,
          value: document.getElementById('progress').hidden ? -1 : document.getElementById('progress').position >= 0 ? document.getElementById('progress').value : -1,
          text: document.getElementById('status').textContent,
        }));
        if (s.run > r0 && s.state !== 'running') return `the job ended (${s.state}: ${s.text}) before it could be canceled`;
        if (s.url) jobUrl = s.url;
        if (s.value > 0 && (!seen.length || s.value !== seen[seen.length - 1])) seen.push(s.value);
        if (seen.length >= 2) break;
        await new Promise((r) => setTimeout(r, 100));
      }
      if (seen.length < 2 || !(seen[1] > seen[0])) return `progress seen: ${seen.join(', ')}`;
      if (outdir) await page.screenshot({ path: path.join(outdir, 'long-job-progress.png') });
      const status = await page.textContent('#status');
      await page.click('#cancel');
      if (await settle(r0, 20000) !== 'canceled') return `after Cancel: ${await page.evaluate(() => window.cellar.state)}: ${await errorText()}`;
      if (!jobUrl) return 'no job URL';
      const job = await getJSON(jobUrl);
      if (job.state !== 'canceled') return `the job is ${job.state}`;
      const shown = await page.textContent('#status');
      if (!/canceled/.test(shown)) return `status "${shown}"`;
      figure(`long job: progress ${seen.map((x) => x.toFixed(2)).join(' -> ')} ("${status}"), then canceled (GET ${jobUrl}: ${job.state})`);
    });
  }

  await check('no uncaught error and no Content-Security-Policy violation in the page', async () => (errors.length ? errors.slice(0, 3).join(' | ') : undefined));
  await browser.close();
}

main().catch((e) => { fail('the browser checks ran', String(e && e.stack ? e.stack : e)); }).finally(() => {
  console.log(`${P} passed, ${F} failed`);
  process.exit(F ? 1 : 0);
});
