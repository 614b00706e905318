#!/usr/bin/env node
// bench/manifold_bool.mjs — the Boolean of closed solids with Manifold (npm manifold-3d, WASM),
// a third reference beside cellar and CGAL (bench/runbool.sh).
//
// Usage: node bench/manifold_bool.mjs [--op union|intersection|difference] [--float32] [--warm]
//            A.off B.off ...
// Prints one JSON line: {"op", "volume", "ms", "inputs", "triangles", "status", "coords"}.
//   op          union (default), intersection, or difference = the first minus all the others;
//   volume      the result's volume (Manifold.volume(): cavities are subtracted);
//   ms          the Boolean only: the batch op and its evaluation (status()), not the reading of
//               the files, the construction of the input Manifolds or the module's start-up;
//   triangles   of the result; status: Manifold's error status of the result ("NoError");
//   coords      "float64" (default) or "float32" (--float32, see below);
//   ms_build    the construction of the input Manifolds from their meshes (new Manifold(mesh)
//               and its status: Manifold's check that each is closed and manifold, its half-edges,
//               normals and collider), the work that cellar's figure counts as its check and
//               input stages; the warp to double coordinates below is not counted; with
//               --warm, each is constructed twice and the second construction timed;
//   ms_warm     with --warm only: the same Boolean run a second time in the process (the first
//               run includes WASM tier-up and heap growth: 3 times slower for 100 cubes, alike
//               for 1000).
// Each OFF face is cut into a fan of triangles; a quad along the diagonal whose two triangles'
// normals agree best (as CGAL's triangulate_faces and cellar do: the same solid when a quad is
// not planar).
// Manifold's JS Mesh holds Float32Array positions; so that it computes with the same doubles as
// cellar and CGAL, each input Manifold's vertices are then put back to the file's doubles with
// warpBatch (keyed by their float32 roundings, which are distinct for the inputs here); --float32
// skips that and keeps the float32 positions.  Exit status 1 on an error (message on stderr).
import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';

let Module;
try {
  ({ default: Module } = await import('manifold-3d'));
} catch (e) {
  console.error('manifold_bool: cannot load manifold-3d (npm install --prefix bench): ' +
                e.message);
  process.exit(2);
}

function usage() {
  console.error('usage: manifold_bool.mjs [--op union|intersection|difference] [--float32] ' +
                'A.off B.off ...');
  process.exit(1);
}

// The dot product of the normals of triangles abc and def (vertex indices into pos).
function dotNormals(pos, a, b, c, d, e, f) {
  const n = (p, q, r) => {
    const u = [0, 1, 2].map((k) => pos[3 * q + k] - pos[3 * p + k]);
    const w = [0, 1, 2].map((k) => pos[3 * r + k] - pos[3 * p + k]);
    return [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
  };
  const x = n(a, b, c), y = n(d, e, f);
  return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
}

// readOff(path): {pos: Float64Array (x,y,z per vertex), tri: Uint32Array (fans of the faces)}.
function readOff(path) {
  const text = readFileSync(path, 'utf8').replace(/#[^\n]*/g, '');
  const tok = text.split(/\s+/).filter((t) => t.length > 0);
  let i = 0;
  const head = tok[i++];
  if (head === undefined || !head.endsWith('OFF')) throw new Error(`${path}: not an OFF file`);
  const nv = Number(tok[i++]), nf = Number(tok[i++]);
  i++; // edges
  if (!(nv >= 0 && nf >= 0)) throw new Error(`${path}: bad OFF header`);
  const pos = new Float64Array(3 * nv);
  for (let k = 0; k < 3 * nv; k++) pos[k] = Number(tok[i++]);
  const tri = [];
  for (let f = 0; f < nf; f++) {
    const n = Number(tok[i++]);
    const v = [];
    for (let k = 0; k < n; k++) {
      const x = Number(tok[i++]);
      if (!(Number.isInteger(x) && x >= 0 && x < nv)) throw new Error(`${path}: bad face ${f}`);
      v.push(x);
    }
    if (n < 3) throw new Error(`${path}: face ${f} has ${n} vertices`);
    if (n === 4) {
      // a quad (planar only up to rounding, or not at all): along the diagonal whose two
      // triangles' normals agree best, as CGAL's triangulate_faces and cellar choose
      const d02 = dotNormals(pos, v[0], v[1], v[2], v[2], v[3], v[0]);
      const d13 = dotNormals(pos, v[1], v[2], v[3], v[3], v[0], v[1]);
      if (d02 > d13) tri.push(v[0], v[1], v[2], v[2], v[3], v[0]);
      else tri.push(v[1], v[2], v[3], v[3], v[0], v[1]);
      continue;
    }
    for (let k = 1; k + 1 < n; k++) tri.push(v[0], v[k], v[k + 1]);
  }
  if (pos.some((x) => !Number.isFinite(x))) throw new Error(`${path}: bad coordinates`);
  return { pos, tri: Uint32Array.from(tri) };
}

const args = process.argv.slice(2);
let op = 'union', float32 = false, warm = false;
const files = [];
for (let k = 0; k < args.length; k++) {
  if (args[k] === '--op' && k + 1 < args.length) op = args[++k];
  else if (args[k] === '--float32') float32 = true;
  else if (args[k] === '--warm') warm = true;
  else if (args[k].startsWith('--')) usage();
  else files.push(args[k]);
}
if (!['union', 'intersection', 'difference'].includes(op) || files.length === 0) usage();

const wasm = await Module();
wasm.setup();
const { Manifold, Mesh } = wasm;

const key = (x, y, z) => `${x},${y},${z}`;
let msBuild = 0; // the input Manifolds' construction from their meshes (see ms_build)
const solids = files.map((path) => {
  const { pos, tri } = readOff(path);
  const mesh = new Mesh({ numProp: 3, vertProperties: Float32Array.from(pos), triVerts: tri });
  if (warm) { // a first construction, not timed (WASM tier-up), as the op's below
    const w = new Manifold(mesh);
    w.status();
    w.delete();
  }
  const tb = performance.now();
  let m = new Manifold(mesh);
  const built = m.status();
  msBuild += performance.now() - tb;
  if (built !== 'NoError') throw new Error(`${path}: not a manifold (${built})`);
  if (!float32) {
    const exact = new Map();
    for (let v = 0; v < pos.length; v += 3) {
      const k = key(Math.fround(pos[v]), Math.fround(pos[v + 1]), Math.fround(pos[v + 2]));
      const prev = exact.get(k);
      if (prev && (prev[0] !== pos[v] || prev[1] !== pos[v + 1] || prev[2] !== pos[v + 2]))
        throw new Error(`${path}: two vertices round to the same float32 point (use --float32)`);
      exact.set(k, [pos[v], pos[v + 1], pos[v + 2]]);
    }
    m = m.warpBatch((verts, count) => {
      for (let v = 0; v < 3 * count; v += 3) {
        const e = exact.get(key(verts[v], verts[v + 1], verts[v + 2]));
        if (!e) throw new Error(`${path}: a vertex Manifold moved`);
        verts[v] = e[0];
        verts[v + 1] = e[1];
        verts[v + 2] = e[2];
      }
    });
    if (m.status() !== 'NoError') throw new Error(`${path}: warped: ${m.status()}`);
  }
  return m;
});

function boolean() {
  const t0 = performance.now();
  let r;
  if (solids.length === 1) r = solids[0];
  else if (op === 'union') r = Manifold.union(solids);
  else if (op === 'intersection') r = Manifold.intersection(solids);
  else r = Manifold.difference(solids);
  const status = r.status(); // evaluates the deferred CSG tree
  return { r, status, ms: performance.now() - t0 };
}
const round = (ms) => Math.round(ms * 1000) / 1000;
const { r, status, ms } = boolean();
const out = {
  op, volume: r.volume(), ms: round(ms), inputs: files.length, triangles: r.numTri(),
  status: String(status), coords: float32 ? 'float32' : 'float64', ms_build: round(msBuild),
};
if (warm) out.ms_warm = round(boolean().ms);
console.log(JSON.stringify(out));
if (status !== 'NoError') process.exit(1);
