// worker.js — off the page's thread: runs a job through the API (api.js), parses its result
// (LAR JSON, README "Results") and makes what the views draw, so that a large result never
// blocks the page.
//   2D: the faces' cycles (outer, then holes) as flat index arrays, each face's area, a point
//       inside it for its number, its centroid and box, a grid of the faces for hover; the
//       edges, which are dangling; the cycles of a Boolean's result region; coordinates
//       mapped to a square of 10^6 units, y down.
//   3D: per bounded cell, triangles (faces triangulated with their holes, turned out of the
//       cell by the sign of CF) and the edges of its faces, in one Float32Array each; the
//       cells' centres; coordinates centred and scaled to a radius of about 1.
// The model's typed arrays are transferred to the page.
import { Earcut } from 'three/src/extras/Earcut.js';
import { Canceled, Problem, startJob } from './api.js';

const SIZE = 1e6;

// Drawing progress: tick(stage, fraction) tells the page how far the preparation of the
// current result is: each new stage at once, and within a stage at most every 100 ms; set by
// the run that prepares it.
let tick = () => {};
function ticker(id) {
  let last = 0, lastStage = '';
  return (stage, fraction) => {
    const t = performance.now();
    if (t - last < 100 && fraction < 1 && stage === lastStage) return;
    last = t;
    lastStage = stage;
    self.postMessage({ id, drawing: { stage, fraction } });
  };
}

function csr(m) {
  if (!m || !Array.isArray(m.indptr)) return null;
  return { indptr: Int32Array.from(m.indptr), indices: Int32Array.from(m.indices), shape: m.shape };
}

function need(r, keys) {
  const miss = keys.filter((k) => !r[k]);
  if (miss.length) throw new Error(`the result has no ${miss.join(', ')}: nothing to draw (its request's options.fields leaves them out)`);
}

// The signed area and the area moments of the cycle c (vertex indices into x, y).
function ring(c, x, y, acc) {
  let a = 0, cx = 0, cy = 0;
  const n = c.length;
  for (let i = 0; i < n; i++) {
    const p = c[i], q = c[i + 1 === n ? 0 : i + 1];
    const cr = x[p] * y[q] - x[q] * y[p];
    a += cr;
    cx += (x[p] + x[q]) * cr;
    cy += (y[p] + y[q]) * cr;
  }
  acc[0] += a / 2;
  acc[1] += cx / 6;
  acc[2] += cy / 6;
}

// Even-odd: is (px, py) inside the cycles?
function inside(cycles, x, y, px, py) {
  let inn = false;
  for (const c of cycles) {
    const n = c.length;
    for (let i = 0, j = n - 1; i < n; j = i++) {
      const xi = x[c[i]], yi = y[c[i]], xj = x[c[j]], yj = y[c[j]];
      if ((yi > py) !== (yj > py) && px < ((xj - xi) * (py - yi)) / (yj - yi) + xi) inn = !inn;
    }
  }
  return inn;
}

// A point inside the face for its number: the centroid when it is inside, else the middle of
// the widest inside stretch of the horizontal line through it.
function labelPoint(cycles, x, y, cx, cy) {
  if (inside(cycles, x, y, cx, cy)) return [cx, cy];
  let ys = cy;
  const xs = [];
  for (let pass = 0; pass < 2 && xs.length < 2; pass++) {
    xs.length = 0;
    for (const c of cycles) {
      const n = c.length;
      for (let i = 0, j = n - 1; i < n; j = i++) {
        const xi = x[c[i]], yi = y[c[i]], xj = x[c[j]], yj = y[c[j]];
        if ((yi > ys) !== (yj > ys)) xs.push(((xj - xi) * (ys - yi)) / (yj - yi) + xi);
      }
    }
    if (xs.length < 2) { // the centroid's line misses: the middle of the first edge's height
      const c = cycles[0];
      ys = (y[c[0]] + y[c[1 % c.length]] + y[c[2 % c.length]]) / 3;
    }
  }
  xs.sort((a, b) => a - b);
  let best = -1, bx = cx;
  for (let i = 0; i + 1 < xs.length; i += 2)
    if (xs[i + 1] - xs[i] > best) { best = xs[i + 1] - xs[i]; bx = (xs[i] + xs[i + 1]) / 2; }
  return [bx, ys];
}

// Cycles as flat arrays: face f's cycles are cycOff[faceCyc[f]] .. cycOff[faceCyc[f + 1]] in
// cyc (vertex indices), its outer cycle first.
function flatCycles(rows, holes) {
  let ncyc = 0, nidx = 0;
  const n = rows.length;
  for (let f = 0; f < n; f++) {
    ncyc += 1;
    nidx += rows[f].length;
    const h = holes && holes[f];
    if (h) for (const c of h) { ncyc++; nidx += c.length; }
  }
  const faceCyc = new Int32Array(n + 1), cycOff = new Int32Array(ncyc + 1), cyc = new Int32Array(nidx);
  let k = 0, p = 0;
  for (let f = 0; f < n; f++) {
    faceCyc[f] = k;
    const h = holes && holes[f];
    for (const c of h ? [rows[f], ...h] : [rows[f]]) {
      cycOff[k++] = p;
      for (const v of c) cyc[p++] = v;
    }
  }
  faceCyc[n] = k;
  cycOff[k] = p;
  return { faceCyc, cycOff, cyc };
}

// A grid over the drawing for hover: the faces whose box meets each cell (cells of about one
// face each), as compressed rows.
function grid(nf, faceCyc, cycOff, cyc, vxy, width, height) {
  const bx = new Float32Array(4 * nf);
  for (let f = 0; f < nf; f++) {
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (let i = cycOff[faceCyc[f]]; i < cycOff[faceCyc[f] + 1]; i++) {
      const x = vxy[2 * cyc[i]], y = vxy[2 * cyc[i] + 1];
      if (x < x0) x0 = x;
      if (x > x1) x1 = x;
      if (y < y0) y0 = y;
      if (y > y1) y1 = y;
    }
    bx[4 * f] = x0; bx[4 * f + 1] = y0; bx[4 * f + 2] = x1; bx[4 * f + 3] = y1;
  }
  const w = Math.max(width, 1), h = Math.max(height, 1);
  const cell = Math.sqrt((w * h) / Math.max(nf, 1)) || 1;
  const gw = Math.min(4096, Math.max(1, Math.ceil(w / cell))), gh = Math.min(4096, Math.max(1, Math.ceil(h / cell)));
  const cw = w / gw, ch = h / gh;
  const range = (f) => [
    Math.max(0, Math.min(gw - 1, Math.floor(bx[4 * f] / cw))), Math.max(0, Math.min(gh - 1, Math.floor(bx[4 * f + 1] / ch))),
    Math.max(0, Math.min(gw - 1, Math.floor(bx[4 * f + 2] / cw))), Math.max(0, Math.min(gh - 1, Math.floor(bx[4 * f + 3] / ch))),
  ];
  const off = new Int32Array(gw * gh + 1);
  for (let f = 0; f < nf; f++) {
    const [i0, j0, i1, j1] = range(f);
    for (let j = j0; j <= j1; j++) for (let i = i0; i <= i1; i++) off[j * gw + i + 1]++;
  }
  for (let c = 0; c < gw * gh; c++) off[c + 1] += off[c];
  const ids = new Int32Array(off[gw * gh]), fill = off.slice(0, gw * gh);
  for (let f = 0; f < nf; f++) {
    const [i0, j0, i1, j1] = range(f);
    for (let j = j0; j <= j1; j++) for (let i = i0; i <= i1; i++) ids[fill[j * gw + i]++] = f;
  }
  return { gw, gh, cw, ch, off, ids, bx };
}

function prep2(r, flipY) {
  need(r, ['V', 'FV']);
  const nv = r.V.length, nf = r.FV.length;
  let minx = Infinity, miny = Infinity, maxx = -Infinity, maxy = -Infinity;
  const wx = new Float64Array(nv), wy = new Float64Array(nv);
  for (let i = 0; i < nv; i++) {
    const p = r.V[i];
    wx[i] = p[0]; wy[i] = p[1];
    if (p[0] < minx) minx = p[0];
    if (p[0] > maxx) maxx = p[0];
    if (p[1] < miny) miny = p[1];
    if (p[1] > maxy) maxy = p[1];
  }
  if (!nv) { minx = miny = 0; maxx = maxy = 1; }
  const ext = Math.max(maxx - minx, maxy - miny) || 1;
  const s = SIZE / ext;
  // view coordinates: [0, 10^6] for the larger side, y down for the screen
  const vxy = new Float32Array(2 * nv), vx = new Float64Array(nv), vy = new Float64Array(nv);
  for (let i = 0; i < nv; i++) {
    vx[i] = (wx[i] - minx) * s;
    vy[i] = flipY ? (maxy - wy[i]) * s : (wy[i] - miny) * s;
    vxy[2 * i] = vx[i]; vxy[2 * i + 1] = vy[i];
  }
  const { faceCyc, cycOff, cyc } = flatCycles(r.FV, r.holes);
  const sel = new Uint8Array(nf);
  const res = r.result && Array.isArray(r.result.cells) ? r.result : null;
  if (res) for (const f of res.cells) if (f < nf) sel[f] = 1;
  const area = new Float64Array(nf), nholes = new Int32Array(nf);
  const lx = new Float32Array(nf), ly = new Float32Array(nf);
  const cx = new Float32Array(nf), cy = new Float32Array(nf);
  const acc = [0, 0, 0], vacc = [0, 0, 0];
  const cycles = [];
  for (let f = 0; f < nf; f++) {
    if ((f & 1023) === 0) tick('faces', 0.1 + (0.6 * f) / nf);
    acc[0] = acc[1] = acc[2] = 0;
    vacc[0] = vacc[1] = vacc[2] = 0;
    cycles.length = 0;
    for (let k = faceCyc[f]; k < faceCyc[f + 1]; k++) {
      const c = cyc.subarray(cycOff[k], cycOff[k + 1]);
      cycles.push(c);
      ring(c, wx, wy, acc);
      ring(c, vx, vy, vacc);
    }
    area[f] = Math.abs(acc[0]);
    nholes[f] = faceCyc[f + 1] - faceCyc[f] - 1;
    const a = vacc[0] || 1;
    const gx = vacc[1] / a, gy = vacc[2] / a;
    cx[f] = gx; cy[f] = gy;
    const [px, py] = labelPoint(cycles, vx, vy, gx, gy);
    lx[f] = px; ly[f] = py;
  }
  // edges; those in no face's boundary (FE) are dangling
  const ne = r.EV ? r.EV.length : 0;
  const ev = new Int32Array(2 * ne), dangling = new Uint8Array(ne);
  for (let e = 0; e < ne; e++) { ev[2 * e] = r.EV[e][0]; ev[2 * e + 1] = r.EV[e][1]; }
  if (r.FE) {
    dangling.fill(1);
    for (const row of r.FE) for (const e of row) dangling[Math.abs(e) - 1] = 0;
  }
  const out = res && res.FV ? flatCycles(res.FV, res.holes) : null;
  const width = (maxx - minx) * s, height = (maxy - miny) * s;
  tick('hover grid', 0.75);
  const g = grid(nf, faceCyc, cycOff, cyc, vxy, width, height);
  return {
    dim: 2, faces: nf, vertices: nv, edges: ne, width, height,
    world: { minx, miny, maxx, maxy, s, flipY },
    vxy, faceCyc, cycOff, cyc, ev, dangling, area, nholes, lx, ly, cx, cy, sel,
    outCycOff: out ? out.cycOff : null, outCyc: out ? out.cyc : null,
    grid: { gw: g.gw, gh: g.gh, cw: g.cw, ch: g.ch }, gridOff: g.off, gridIds: g.ids, box: g.bx,
    membership: csr(r.membership),
    result: res ? { cells: res.cells.length, area: res.area, polygons: res.FV ? res.FV.length : 0 } : null,
    layers: Array.isArray(r.layers) ? r.layers : null,
    stats: r.stats || null,
  };
}

// Newell's normal of the cycle c of points P (flat xyz).
function newell(c, P) {
  let nx = 0, ny = 0, nz = 0;
  for (let i = 0, n = c.length; i < n; i++) {
    const a = 3 * c[i], b = 3 * c[(i + 1) % n];
    nx += (P[a + 1] - P[b + 1]) * (P[a + 2] + P[b + 2]);
    ny += (P[a + 2] - P[b + 2]) * (P[a] + P[b]);
    nz += (P[a] - P[b]) * (P[a + 1] + P[b + 1]);
  }
  const l = Math.hypot(nx, ny, nz) || 1;
  return [nx / l, ny / l, nz / l];
}

// Triangles of face f as vertex index triples, counter-clockwise seen from the tip of its
// normal (the outer cycle's orientation).
function triangulate(cycles, P, nrm) {
  const ax = Math.abs(nrm[0]), ay = Math.abs(nrm[1]), az = Math.abs(nrm[2]);
  // drop the axis the normal is closest to; keep the projection's orientation positive
  const [u, v] = az >= ax && az >= ay ? (nrm[2] > 0 ? [0, 1] : [1, 0])
    : ax >= ay ? (nrm[0] > 0 ? [1, 2] : [2, 1]) : (nrm[1] > 0 ? [2, 0] : [0, 2]);
  const flat = [], holeIdx = [], ids = [];
  cycles.forEach((c, k) => {
    if (k) holeIdx.push(ids.length);
    for (const i of c) { flat.push(P[3 * i + u], P[3 * i + v]); ids.push(i); }
  });
  if (cycles.length === 1 && ids.length === 3) return ids;
  const t = Earcut.triangulate(flat, holeIdx, 2);
  const out = new Array(t.length);
  for (let i = 0; i < t.length; i += 3) {
    const a = t[i], b = t[i + 1], c = t[i + 2];
    const cr = (flat[2 * b] - flat[2 * a]) * (flat[2 * c + 1] - flat[2 * a + 1]) -
      (flat[2 * b + 1] - flat[2 * a + 1]) * (flat[2 * c] - flat[2 * a]);
    out[i] = ids[a];
    out[i + 1] = cr >= 0 ? ids[b] : ids[c];
    out[i + 2] = cr >= 0 ? ids[c] : ids[b];
  }
  return out;
}

function prep3(r) {
  need(r, ['V', 'FV', 'CF']);
  const nv = r.V.length, nf = r.FV.length, nc = r.CF.length;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (const p of r.V) for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[k]); hi[k] = Math.max(hi[k], p[k]); }
  const mid = lo.map((a, k) => (a + hi[k]) / 2);
  const ext = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
  const s = 2 / ext;
  const P = new Float64Array(3 * nv);
  for (let i = 0; i < nv; i++) for (let k = 0; k < 3; k++) P[3 * i + k] = (r.V[i][k] - mid[k]) * s;
  const holes = r.holes || {};
  const tris = new Array(nf), nrms = new Array(nf);
  let triCount = 0, segCount = 0;
  for (let f = 0; f < nf; f++) {
    if ((f & 255) === 0) tick('triangulating', 0.1 + (0.6 * f) / nf);
    const cycles = holes[f] ? [r.FV[f], ...holes[f]] : [r.FV[f]];
    nrms[f] = newell(r.FV[f], P);
    tris[f] = triangulate(cycles, P, nrms[f]);
  }
  // sizes first, then one buffer each for triangles (xyz + normal) and edges
  const triOff = new Int32Array(nc + 1), segOff = new Int32Array(nc + 1);
  for (let c = 0; c < nc; c++) {
    let t = 0, e = 0;
    for (const sf of r.CF[c]) {
      const f = Math.abs(sf) - 1;
      t += tris[f].length / 3;
      e += r.FV[f].length;
      for (const h of holes[f] || []) e += h.length;
    }
    triOff[c + 1] = triOff[c] + t;
    segOff[c + 1] = segOff[c] + e;
  }
  triCount = triOff[nc];
  segCount = segOff[nc];
  const pos = new Float32Array(9 * triCount), nor = new Float32Array(9 * triCount);
  const seg = new Float32Array(6 * segCount);
  const centre = new Float32Array(3 * nc);
  let tp = 0, sp = 0;
  for (let c = 0; c < nc; c++) {
    const seen = new Set();
    for (const sf of r.CF[c]) {
      const f = Math.abs(sf) - 1, t = tris[f], n = nrms[f], sg = sf > 0 ? 1 : -1;
      for (let i = 0; i < t.length; i += 3) {
        const a = t[i], b = sg > 0 ? t[i + 1] : t[i + 2], d = sg > 0 ? t[i + 2] : t[i + 1];
        for (const v of [a, b, d]) {
          pos[tp] = P[3 * v]; pos[tp + 1] = P[3 * v + 1]; pos[tp + 2] = P[3 * v + 2];
          nor[tp] = sg * n[0]; nor[tp + 1] = sg * n[1]; nor[tp + 2] = sg * n[2];
          tp += 3;
        }
      }
      for (const cyc of holes[f] ? [r.FV[f], ...holes[f]] : [r.FV[f]]) {
        for (let i = 0; i < cyc.length; i++) {
          const a = cyc[i], b = cyc[(i + 1) % cyc.length];
          seg[sp] = P[3 * a]; seg[sp + 1] = P[3 * a + 1]; seg[sp + 2] = P[3 * a + 2];
          seg[sp + 3] = P[3 * b]; seg[sp + 4] = P[3 * b + 1]; seg[sp + 5] = P[3 * b + 2];
          sp += 6;
          seen.add(a);
        }
      }
    }
    const verts = r.CV && r.CV[c] ? r.CV[c] : [...seen];
    let x = 0, y = 0, z = 0;
    for (const v of verts) { x += P[3 * v]; y += P[3 * v + 1]; z += P[3 * v + 2]; }
    const k = verts.length || 1;
    centre[3 * c] = x / k; centre[3 * c + 1] = y / k; centre[3 * c + 2] = z / k;
  }
  const res = r.result && Array.isArray(r.result.cells) ? r.result : null;
  const sel = new Uint8Array(nc);
  if (res) for (const c of res.cells) if (c < nc) sel[c] = 1;
  const cf = r.CF.map((row) => row.join(' '));
  // the result as one solid: its boundary faces (result.faces, signed as CF's rows: outward),
  // else the faces of its cells that no other result cell shares
  let rfaces = res && Array.isArray(res.faces) ? res.faces : null;
  if (res && !rfaces) {
    const n = new Map();
    for (const c of res.cells) for (const sf of r.CF[c] || []) n.set(Math.abs(sf), (n.get(Math.abs(sf)) || 0) + 1);
    rfaces = [];
    for (const c of res.cells) for (const sf of r.CF[c] || []) if (n.get(Math.abs(sf)) === 1) rfaces.push(sf);
  }
  let resPos = null, resNor = null, resSeg = null;
  if (rfaces) {
    let t = 0, e = 0;
    for (const sf of rfaces) {
      const f = Math.abs(sf) - 1;
      if (f >= nf) continue;
      t += tris[f].length / 3;
      e += r.FV[f].length;
      for (const h of holes[f] || []) e += h.length;
    }
    resPos = new Float32Array(9 * t);
    resNor = new Float32Array(9 * t);
    resSeg = new Float32Array(6 * e);
    let q = 0, w = 0;
    for (const sf of rfaces) {
      const f = Math.abs(sf) - 1;
      if (f >= nf) continue;
      const tr = tris[f], n = nrms[f], sg = sf > 0 ? 1 : -1;
      for (let i = 0; i < tr.length; i += 3) {
        for (const v of [tr[i], sg > 0 ? tr[i + 1] : tr[i + 2], sg > 0 ? tr[i + 2] : tr[i + 1]]) {
          resPos[q] = P[3 * v]; resPos[q + 1] = P[3 * v + 1]; resPos[q + 2] = P[3 * v + 2];
          resNor[q] = sg * n[0]; resNor[q + 1] = sg * n[1]; resNor[q + 2] = sg * n[2];
          q += 3;
        }
      }
      for (const cyc of holes[f] ? [r.FV[f], ...holes[f]] : [r.FV[f]]) {
        for (let i = 0; i < cyc.length; i++) {
          const a = cyc[i], b = cyc[(i + 1) % cyc.length];
          resSeg.set([P[3 * a], P[3 * a + 1], P[3 * a + 2], P[3 * b], P[3 * b + 1], P[3 * b + 2]], w);
          w += 6;
        }
      }
    }
  }
  return {
    dim: 3, cells: nc, faces: nf, vertices: nv, edges: r.EV ? r.EV.length : 0,
    pos, nor, seg, triOff, segOff, centre, sel, cf, resPos, resNor, resSeg,
    volumes: r.stats && r.stats.volumes ? Float64Array.from(r.stats.volumes) : null,
    membership: csr(r.membership),
    result: res ? { cells: res.cells.length, volume: res.volume, faces: rfaces.length } : null,
    layers: Array.isArray(r.layers) ? r.layers : null,
    stats: r.stats ? { ...r.stats, volumes: undefined } : null,
  };
}

// The paths of a 2D model as SVG path data, in view units (Path2D parses these far faster
// than it takes as many moveTo/lineTo calls): the faces in BUCKETS colours by face % BUCKETS
// (a Boolean's faces outside its result in `grey`), each face moved by (k - 1) times its
// centroid's distance from the drawing's centre (the faces' outlines are these paths
// stroked); the dangling edges and the result's outline (not exploded only).
const BUCKETS = 48;
function paths2(m, k) {
  const { faceCyc, cycOff, cyc, vxy, cx, cy, sel } = m;
  const t = k - 1, boolean = !!m.result, hx = m.width / 2, hy = m.height / 2;
  const fills = Array.from({ length: BUCKETS }, () => []), grey = [], region = [];
  const num = Math.round; // integers: a millionth of the drawing, and far faster to write
  let selected = 0;
  for (let f = 0; f < m.faces; f++) {
    const dx = t ? (cx[f] - hx) * t : 0, dy = t ? (cy[f] - hy) * t : 0;
    let d = '';
    for (let c = faceCyc[f]; c < faceCyc[f + 1]; c++) {
      const a = cycOff[c], b = cycOff[c + 1];
      d += `M${num(vxy[2 * cyc[a]] + dx)} ${num(vxy[2 * cyc[a] + 1] + dy)}`;
      for (let i = a + 1; i < b; i++) d += `L${num(vxy[2 * cyc[i]] + dx)} ${num(vxy[2 * cyc[i] + 1] + dy)}`;
      d += 'Z';
    }
    const on = !boolean || sel[f];
    if (boolean && on) { selected++; region.push(d); }
    (on ? fills[f % BUCKETS] : grey).push(d);
  }
  let dangling = '', outline = '', ndangling = 0;
  if (!t) {
    const { ev } = m;
    for (let e = 0; e < m.edges; e++) {
      if (!m.dangling[e]) continue;
      ndangling++;
      const a = ev[2 * e], b = ev[2 * e + 1];
      dangling += `M${num(vxy[2 * a])} ${num(vxy[2 * a + 1])}L${num(vxy[2 * b])} ${num(vxy[2 * b + 1])}`;
    }
    if (m.outCyc) {
      for (let c = 0; c + 1 < m.outCycOff.length; c++) {
        const a = m.outCycOff[c], b = m.outCycOff[c + 1];
        if (b <= a) continue;
        outline += `M${num(vxy[2 * m.outCyc[a]])} ${num(vxy[2 * m.outCyc[a] + 1])}`;
        for (let i = a + 1; i < b; i++) outline += `L${num(vxy[2 * m.outCyc[i]])} ${num(vxy[2 * m.outCyc[i] + 1])}`;
        outline += 'Z';
      }
    }
  }
  return {
    fills: fills.map((x) => x.join('')), grey: grey.join(''), region: region.join(''), dangling, outline,
    explode: k, faces: m.faces, selected, dangling_edges: ndangling,
  };
}

// the typed arrays of a model, copied: the worker keeps its own to make paths again
function copyArrays(model) {
  const out = {};
  for (const [k, v] of Object.entries(model)) out[k] = ArrayBuffer.isView(v) ? v.slice() : v;
  if (model.membership) out.membership = { ...model.membership, indptr: model.membership.indptr.slice(), indices: model.membership.indices.slice() };
  return out;
}

// ---- messages ------------------------------------------------------------------------------
// in:  {id, run: {base, body, flipY}}  runs the job (api.js) at the service under base (the
//        page's URL), then prepares its result; answers {id, sent: {loaded, total}} as the
//        request goes, {id, job, url} for every status read, {id, got: {loaded, total}} as the
//        result comes, {id, received: {hash, bytes}} once it is in, {id, drawing: {stage,
//        fraction}} as it is prepared, then {id, model}, or {id, error: {status, title,
//        detail, path} | {canceled} | {message}} (a Cancel while the result is prepared: the
//        page terminates this worker, which is busy and hears no message);
//      {cancel: id}               cancels that run's submission;
//      {id, explode: k}           answers {id, paths} of the last 2D result exploded by k.
// The network and the parsing stay off the page's thread: a result of many megabytes is read
// and parsed here.

let last2 = null; // the last 2D model, for explode
const runs = new Map();

function prepareResult(buffer, flipY) {
  const t0 = performance.now();
  tick('parsing the JSON', 0);
  const r = JSON.parse(new TextDecoder().decode(buffer));
  const t1 = performance.now();
  tick('parsed', 0.1);
  if (!r || typeof r !== 'object') throw new Error('the result is not a JSON object');
  let model;
  if (r.dim === 3) {
    model = prep3(r);
    last2 = null;
  } else {
    last2 = prep2(r, flipY);
    const t2 = performance.now();
    model = copyArrays(last2);
    const t3 = performance.now();
    tick('paths', 0.85);
    model.paths = paths2(last2, 1);
    model.ms = { prep2: t2 - t1, copy: t3 - t2, paths: performance.now() - t3 };
  }
  model.ms = { ...model.ms, parse: t1 - t0, prepare: performance.now() - t1 };
  tick('prepared', 1);
  return model;
}

function errorOf(e) {
  if (e instanceof Canceled) return { canceled: true };
  if (e instanceof Problem) return { status: e.status, title: e.title, detail: e.detail, path: e.path };
  return { message: String(e && e.message ? e.message : e) };
}

async function run(id, { base, body, flipY }) {
  const job = startJob(base, body, {
    onJob: (j, url) => self.postMessage({ id, job: j, url }),
    onSent: (loaded, total) => self.postMessage({ id, sent: { loaded, total } }),
    onGot: (loaded, total) => self.postMessage({ id, got: { loaded, total } }),
  });
  runs.set(id, job);
  try {
    const got = await job.done;
    runs.delete(id);
    self.postMessage({ id, received: { hash: got.hash, bytes: got.buffer.byteLength } });
    tick = ticker(id);
    const model = prepareResult(got.buffer, flipY);
    model.hash = got.hash;
    model.bytes = got.buffer.byteLength;
    const transfer = Object.values(model).filter((v) => ArrayBuffer.isView(v)).map((v) => v.buffer);
    if (model.membership) transfer.push(model.membership.indptr.buffer, model.membership.indices.buffer);
    self.postMessage({ id, model }, transfer);
  } catch (e) {
    self.postMessage({ id, error: errorOf(e) });
  } finally {
    runs.delete(id);
    tick = () => {};
  }
}

self.onmessage = (ev) => {
  const d = ev.data;
  if (d.cancel !== undefined) {
    const job = runs.get(d.cancel);
    if (job) job.cancel().catch((e) => self.postMessage({ id: d.cancel, cancelError: errorOf(e) }));
    return;
  }
  if (d.run) {
    run(d.id, d.run);
    return;
  }
  try {
    if (!last2) throw new Error('no 2D result to explode');
    self.postMessage({ id: d.id, paths: paths2(last2, d.explode) });
  } catch (e) {
    self.postMessage({ id: d.id, error: errorOf(e) });
  }
};
