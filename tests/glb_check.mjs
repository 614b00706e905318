// glb_check.mjs RESULT.json FILE.glb [EXPLODED] — a .glb written by cellar (--format glb,
// ?format=glb) opened by an independent reader, three.js's GLTFLoader (web/node_modules/three),
// and checked against the result's own numbers: one mesh per cell, each its own node named
// "cellN", and a Boolean's result as one more node "result"; per node the vertices (the
// distinct vertices of its faces) and triangles (a face of n ring vertices and h holes is
// n - 2 + 2h triangles), every index below the vertex count, the positions those of the
// result's vertices (as float32).  With EXPLODED, some cell node is translated.  Prints
// "ok NAME" / "FAIL NAME: why" per check and "N passed, N failed" last (run by t_meshio.sh).
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const three = path.join(here, '..', 'web', 'node_modules', 'three');
const { GLTFLoader } = await import(
  pathToFileURL(path.join(three, 'examples', 'jsm', 'loaders', 'GLTFLoader.js')).href);

const [resultPath, glbPath, exploded] = process.argv.slice(2);
let P = 0, F = 0;
const ok = (name) => { P++; console.log(`ok ${name}`); };
const fail = (name, why) => { F++; console.log(`FAIL ${name}: ${why}`); };

const res = JSON.parse(fs.readFileSync(resultPath, 'utf8'));
const bytes = fs.readFileSync(glbPath);
const ab = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);

// what a cell (a list of signed faces) should give
function expect(faces) {
  const verts = new Set();
  let tris = 0;
  for (const s of faces) {
    const f = Math.abs(s) - 1;
    const rings = [res.FV[f], ...((res.holes && res.holes[String(f)]) || [])];
    let n = 0;
    for (const r of rings) { n += r.length; for (const v of r) verts.add(v); }
    tris += n - 2 + 2 * (rings.length - 1);
  }
  return { verts, tris };
}

const gltf = await new Promise((resolve, reject) =>
  new GLTFLoader().parse(ab, '', resolve, reject));
const scene = gltf.scene;
const nodes = scene.children;
const cells = res.CF.length, hasResult = !!res.result;
const want = cells + (hasResult ? 1 : 0);
if (nodes.length === want) ok(`${path.basename(glbPath)}: ${nodes.length} nodes`);
else fail('nodes', `${nodes.length} nodes, want ${want} (${cells} cells${hasResult ? ' + result' : ''})`);

const f32 = (x) => Math.fround(x);
let moved = 0;
nodes.forEach((node, i) => {
  const isResult = hasResult && i === cells;
  const name = isResult ? 'result' : `cell${i}`;
  if (node.name !== name) { fail(`node ${i}`, `named "${node.name}", want "${name}"`); return; }
  if (!node.isMesh) { fail(name, 'not a mesh'); return; }
  const e = expect(isResult ? res.result.faces : res.CF[i]);
  const g = node.geometry;
  const nv = g.attributes.position.count, nt = g.index.count / 3;
  if (nv !== e.verts.size || nt !== e.tris) {
    fail(name, `${nv} vertices and ${nt} triangles, want ${e.verts.size} and ${e.tris}`);
    return;
  }
  const pos = g.attributes.position.array, idx = g.index.array;
  for (let k = 0; k < idx.length; k++)
    if (idx[k] >= nv) { fail(name, `index ${idx[k]} of ${nv} vertices`); return; }
  // every position is one of the cell's vertices as float32
  const keys = new Set([...e.verts].map((v) => res.V[v].map(f32).join(',')));
  for (let k = 0; k < nv; k++) {
    const key = [pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]].join(',');
    if (!keys.has(key)) { fail(name, `position ${key} is none of its vertices`); return; }
  }
  if (node.position.lengthSq() > 0) moved++;
  ok(`${name}: ${nv} vertices, ${nt} triangles`);
});
if (exploded) {
  if (moved > 0) ok(`exploded: ${moved} nodes translated`);
  else fail('exploded', 'no node translated');
}
console.log(`${P} passed, ${F} failed`);
process.exit(F ? 1 : 0);
