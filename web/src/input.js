// input.js — files to requests (README, "Requests"):
//   an SVG drawing      -> {"kind": "svg", "svg": TEXT, "options": {"y_up": true}}
//   mesh files          -> {"kind": "solids", "solids": [{V, FV}, ...]}: a solid per file (as
//                          `cellar solids A.obj B.off` reads them), and per object ("o") of an
//                          OBJ file, "solid" of an ASCII STL file and mesh object of a 3MF
//                          file that holds several.  OBJ, OFF; STL, binary and ASCII (its
//                          triangles' corners welded into vertices where bit-identical); PLY,
//                          ascii and binary (either byte order); 3MF (a zip: its .model entry
//                          inflated by the browser's DecompressionStream, read by DOMParser)
//   a JSON request      -> sent as it is (an object with a "kind")
//   GeoJSON             -> {"kind": "polygons", "polygons": [...], "op": "union"}: a polygon
//                          per Polygon or MultiPolygon feature (a .geojson file, or JSON whose
//                          "type" is GeoJSON's)
//   several GeoJSON     -> {"kind": "polygons", "layers": {NAME: FeatureCollection | [polygon,
//                          ...], ...}, "op": "union"}: a layer per file, named by the file's
//                          name without its extension (in the files' order), its features
//                          the inputs, layer after layer; op's names are the layers'
// Each function returns {request, label, names, defaultOp} (names: the inputs' names, for
// membership; defaultOp: the op the input gets when the user chose none) or throws an Error
// whose message names the file and the line.

const GEOJSON_TYPES = new Set(['FeatureCollection', 'Feature', 'Polygon', 'MultiPolygon',
  'GeometryCollection']);

const MESH = new Set(['obj', 'off', 'stl', 'ply', '3mf']);

export function kindOf(name) {
  const m = /\.([a-z0-9]+)$/i.exec(name);
  const ext = m ? m[1].toLowerCase() : '';
  if (ext === 'svg') return 'svg';
  if (MESH.has(ext)) return ext;
  if (ext === 'geojson') return 'geojson';
  if (ext === 'json') return 'json';
  return '';
}

const textOf = (f) => (f.text !== undefined ? f.text : (f.text = new TextDecoder().decode(f.bytes)));
const bytesOf = (f) => (f.bytes !== undefined ? f.bytes : (f.bytes = new TextEncoder().encode(f.text)));

function parseJSON(f) {
  try {
    return JSON.parse(textOf(f));
  } catch (e) {
    throw new Error(`${f.name}: not JSON: ${e.message}`);
  }
}
const isGeoJSON = (doc) => !!(doc && typeof doc === 'object' && GEOJSON_TYPES.has(doc.type) && !doc.kind);

// files: [{name, bytes (a Uint8Array) or text}]; a Promise (a 3MF file is inflated)
export async function requestFromFiles(files) {
  if (!files.length) throw new Error('no file');
  const kinds = files.map((f) => {
    const k = kindOf(f.name);
    if (!k) throw new Error(`${f.name}: not an SVG, OBJ, OFF, STL, PLY, 3MF, JSON or GeoJSON file (by its extension)`);
    return k;
  });
  if (kinds.every((k) => MESH.has(k))) return solidsRequest(files);
  if (files.length > 1) {
    if (kinds.every((k) => k === 'geojson' || k === 'json')) {
      const docs = files.map((f, i) => {
        const d = parseJSON(f);
        if (kinds[i] === 'json' && !isGeoJSON(d)) throw new Error(`${f.name}: not GeoJSON: several JSON files are layers of GeoJSON polygons`);
        return d;
      });
      return layersRequest(docs, files.map((f) => f.name));
    }
    throw new Error('one SVG or JSON request at a time (several files: meshes, a solid each, or GeoJSON files, a layer each)');
  }
  const [f] = files;
  if (kinds[0] === 'svg') {
    if (!/<svg[\s>]/.test(textOf(f))) throw new Error(`${f.name}: no <svg> element: not an SVG drawing`);
    return { request: { kind: 'svg', svg: textOf(f), options: { y_up: true } }, label: f.name, names: [] };
  }
  const doc = parseJSON(f);
  if (kinds[0] === 'geojson' || isGeoJSON(doc)) return geojsonRequest(doc, f.name);
  if (!doc || typeof doc !== 'object' || Array.isArray(doc) || typeof doc.kind !== 'string')
    throw new Error(`${f.name}: not a request (a JSON object with a "kind": lines, svg, polygons, solids) nor GeoJSON`);
  return { request: doc, label: f.name, names: namesOf(doc) };
}

// The inputs' names of a request, for membership (polygon i, solid i).
export function namesOf(req) {
  if (req.kind === 'polygons' && req.layers && typeof req.layers === 'object') {
    const out = [];
    for (const [name, l] of Object.entries(req.layers)) {
      const list = l && l.type === 'FeatureCollection' && Array.isArray(l.features) ? l.features : Array.isArray(l) ? l : [];
      list.forEach((ft, i) => out.push(`${name}: ${ft && ft.type === 'Feature' ? featureName(ft, i) : `polygon ${i}`}`));
    }
    return out;
  }
  if (req.kind === 'polygons') {
    const p = req.polygons;
    if (p && p.type === 'FeatureCollection' && Array.isArray(p.features))
      return p.features.map((ft, i) => featureName(ft, i));
    return Array.isArray(p) ? p.map((_, i) => `polygon ${i}`) : [];
  }
  if (req.kind === 'solids' && Array.isArray(req.solids)) return req.solids.map((_, i) => `solid ${i}`);
  return [];
}

function featureName(ft, i) {
  const p = ft && ft.properties;
  const n = p && (p.name ?? p.NAME ?? p.id ?? p.ID);
  return n !== undefined && n !== null ? String(n) : `feature ${i}`;
}

// The polygons of a GeoJSON document: {polygons (geometries), features (the Features they
// come from, or null: a bare geometry), names, skipped}
function polygonsOf(doc, name) {
  const polygons = [], names = [], features = [];
  let skipped = 0;
  const add = (g, label, ft) => {
    if (!g || typeof g !== 'object') { skipped++; return; }
    if (g.type === 'Polygon' || g.type === 'MultiPolygon') {
      polygons.push(g);
      names.push(label);
      features.push(ft);
    } else if (g.type === 'GeometryCollection' && Array.isArray(g.geometries)) {
      g.geometries.forEach((x, j) => add(x, `${label}.${j}`, ft && { ...ft, geometry: x }));
    } else skipped++;
  };
  if (doc.type === 'FeatureCollection') {
    if (!Array.isArray(doc.features)) throw new Error(`${name}: a FeatureCollection without "features"`);
    doc.features.forEach((ft, i) => add(ft && ft.geometry, featureName(ft, i), ft));
  } else if (doc.type === 'Feature') add(doc.geometry, featureName(doc, 0), doc);
  else add(doc, 'geometry 0', null);
  if (!polygons.length)
    throw new Error(`${name}: no Polygon or MultiPolygon in this GeoJSON (${skipped} other geometries)`);
  return { polygons, names, features, skipped };
}

const leftOut = (n) => (n ? ` (${n} feature${n > 1 ? 's' : ''} without a polygon left out)` : '');

export function geojsonRequest(doc, name) {
  const { polygons, names, skipped } = polygonsOf(doc, name);
  const request = { kind: 'polygons', polygons, op: 'union' };
  return { request, label: `${name}: ${polygons.length} polygons${leftOut(skipped)}`, names, defaultOp: 'union' };
}

// Several GeoJSON documents as layers: each a FeatureCollection of its polygon features (a
// document of features), or the list of its polygons (bare geometries), named by its file's
// name without the extension (made unique with "-2", "-3"...).
export function layersRequest(docs, fileNames) {
  const layers = {}, names = [], labels = [];
  docs.forEach((doc, i) => {
    const file = fileNames[i];
    const base = file.replace(/\.[^.]*$/, '') || `layer ${i}`;
    let name = base;
    for (let k = 2; Object.hasOwn(layers, name); k++) name = `${base}-${k}`;
    const p = polygonsOf(doc, file);
    layers[name] = p.features.every((ft) => ft)
      ? { type: 'FeatureCollection', features: p.features.map((ft, j) => ({ ...ft, geometry: p.polygons[j] })) }
      : p.polygons;
    for (const n of p.names) names.push(`${name}: ${n}`);
    labels.push(`${name} (${p.polygons.length} polygons${leftOut(p.skipped)})`);
  });
  const request = { kind: 'polygons', layers, op: 'union' };
  return { request, label: `${docs.length} layers: ${labels.join(', ')}`, names, defaultOp: 'union' };
}

export async function solidsRequest(files) {
  const solids = [], names = [];
  for (const f of files) {
    const k = kindOf(f.name);
    const parts = k === 'off' ? [readOff(textOf(f), f.name)]
      : k === 'stl' ? readStl(bytesOf(f), f.name)
        : k === 'ply' ? [readPly(bytesOf(f), f.name)]
          : k === '3mf' ? await read3mf(bytesOf(f), f.name)
            : readObj(textOf(f), f.name);
    for (const p of parts) {
      solids.push({ V: p.V, FV: p.FV });
      names.push(p.name ? `${f.name}:${p.name}` : f.name);
    }
  }
  const request = { kind: 'solids', solids };
  return { request, label: `${names.join(', ')}: ${solids.length} solid${solids.length > 1 ? 's' : ''}`, names };
}

function num(tok, file, line) {
  const x = Number(tok);
  if (tok === '' || !Number.isFinite(x)) throw new Error(`${file}: line ${line}: malformed number '${tok.slice(0, 20)}'`);
  return x;
}

// OBJ: "v x y z [w | r g b [a]]", "f a b c ..." (a, a/t, a/t/n, a//n; negative: relative);
// "o NAME" starts an object; anything else is not geometry.  Indices are global in the file;
// each object with faces becomes a solid with the vertices its faces use.
export function readObj(text, file) {
  const V = [];
  const objects = [];
  let cur = { name: '', FV: [] };
  const lines = text.split(/\r\n|\r|\n/);
  for (let i = 0; i < lines.length; i++) {
    const t = lines[i].replace(/#.*/, '').trim();
    if (!t) continue;
    const tok = t.split(/\s+/);
    if (tok[0] === 'v') {
      const n = tok.length - 1;
      if (n < 3 || n > 7) throw new Error(`${file}: line ${i + 1}: a vertex has 3 coordinates, this one ${n}`);
      V.push([num(tok[1], file, i + 1), num(tok[2], file, i + 1), num(tok[3], file, i + 1)]);
    } else if (tok[0] === 'f') {
      const face = [];
      for (const r of tok.slice(1)) {
        const m = /^(-?\d+)(\/-?\d*)?(\/-?\d*)?$/.exec(r);
        if (!m) throw new Error(`${file}: line ${i + 1}: malformed vertex reference '${r.slice(0, 20)}'`);
        const a = parseInt(m[1], 10);
        const v = a > 0 ? a - 1 : V.length + a;
        if (a === 0 || v < 0 || v >= V.length)
          throw new Error(`${file}: line ${i + 1}: vertex index ${a} out of range (${V.length} vertices so far; indices start at 1)`);
        face.push(v);
      }
      if (face.length < 3) throw new Error(`${file}: line ${i + 1}: a face needs 3 vertices, this one has ${face.length}`);
      cur.FV.push(face);
    } else if (tok[0] === 'o') {
      if (cur.FV.length) objects.push(cur);
      cur = { name: tok.slice(1).join(' '), FV: [] };
    }
  }
  if (cur.FV.length) objects.push(cur);
  if (!objects.length) throw new Error(`${file}: no faces ("f" lines): not a solid`);
  if (objects.length === 1) return [{ name: '', V, FV: objects[0].FV }];
  return objects.map((o) => {
    const map = new Map(), v = [];
    const FV = o.FV.map((c) => c.map((k) => {
      if (!map.has(k)) { map.set(k, v.length); v.push(V[k]); }
      return map.get(k);
    }));
    return { name: o.name, V: v, FV };
  });
}

// OFF: a header [ST][C][N][4][n]OFF (only 3D), then "nv nf ne", nv vertices (the first three
// numbers of each line), nf faces "n i0 ... i(n-1) [colour]"; '#' starts a comment.
export function readOff(text, file) {
  const lines = text.split(/\r\n|\r|\n/);
  let i = 0;
  const next = () => {
    while (i < lines.length) {
      const t = lines[i++].replace(/#.*/, '').trim();
      if (t) return t.split(/\s+/);
    }
    throw new Error(`${file}: the file ends early (line ${i})`);
  };
  let tok = next();
  const head = /^(ST)?C?N?(4?)(n?)OFF$/.exec(tok[0]);
  if (!head) throw new Error(`${file}: line ${i}: expected an OFF header, found '${tok[0].slice(0, 20)}'`);
  if (head[2] || head[3]) throw new Error(`${file}: line ${i}: ${tok[0]}: only 3D OFF files are solids`);
  tok = tok.slice(1);
  if (!tok.length) tok = next();
  const nv = num(tok[0], file, i), nf = num(tok[1] ?? '', file, i);
  if (!Number.isInteger(nv) || !Number.isInteger(nf) || nv < 0 || nf < 0)
    throw new Error(`${file}: line ${i}: expected the counts "vertices faces edges"`);
  const V = [], FV = [];
  for (let k = 0; k < nv; k++) {
    const t = next();
    if (t.length < 3) throw new Error(`${file}: line ${i}: a vertex has 3 coordinates`);
    V.push([num(t[0], file, i), num(t[1], file, i), num(t[2], file, i)]);
  }
  for (let k = 0; k < nf; k++) {
    const t = next();
    const n = num(t[0], file, i);
    if (!Number.isInteger(n) || n < 3 || t.length < n + 1)
      throw new Error(`${file}: line ${i}: a face is "n i0 ... i(n-1)" with n >= 3`);
    const face = [];
    for (let j = 1; j <= n; j++) {
      const v = num(t[j], file, i);
      if (!Number.isInteger(v) || v < 0 || v >= nv)
        throw new Error(`${file}: line ${i}: vertex index ${t[j]} out of range (${nv} vertices; indices start at 0)`);
      face.push(v);
    }
    FV.push(face);
  }
  if (!FV.length) throw new Error(`${file}: no faces: not a solid`);
  return { name: '', V, FV };
}

// Vertices welded where bit-identical: weld(key, [x, y, z]) gives the vertex's index.
function welder() {
  const V = [], map = new Map();
  return {
    V,
    at(key, p) {
      let i = map.get(key);
      if (i === undefined) { i = V.length; map.set(key, i); V.push(p); }
      return i;
    },
  };
}

// STL: binary (an 80-byte header, a triangle count, 50 bytes a triangle: normal, three
// corners as little-endian float32, an attribute word) when its size says so, else ASCII
// ("solid NAME", "facet normal ...", "outer loop", three "vertex x y z", "endloop",
// "endfacet", "endsolid"): a solid per "solid" block.  The corners are welded into vertices
// where their coordinates are bit-identical (the float32 bits, or the numbers read); a
// triangle with two corners the same is left out (none left: an error).
export function readStl(bytes, file) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const head = new TextDecoder().decode(bytes.subarray(0, Math.min(bytes.length, 512)));
  const binary = bytes.length >= 84 && 84 + 50 * dv.getUint32(80, true) === bytes.length;
  if (binary) {
    const n = dv.getUint32(80, true), w = welder(), FV = [];
    for (let t = 0; t < n; t++) {
      const o = 84 + 50 * t + 12, tri = [];
      for (let k = 0; k < 3; k++) {
        const a = o + 12 * k;
        const key = `${dv.getUint32(a, true)},${dv.getUint32(a + 4, true)},${dv.getUint32(a + 8, true)}`;
        const p = [dv.getFloat32(a, true), dv.getFloat32(a + 4, true), dv.getFloat32(a + 8, true)];
        if (!p.every(Number.isFinite)) throw new Error(`${file}: triangle ${t}: a coordinate is not a finite number`);
        tri.push(w.at(key, p));
      }
      if (tri[0] !== tri[1] && tri[1] !== tri[2] && tri[0] !== tri[2]) FV.push(tri);
    }
    if (!FV.length) throw new Error(`${file}: no triangles (a binary STL file of ${n})`);
    return [{ name: '', V: w.V, FV }];
  }
  if (!/^\s*solid\b/.test(head))
    throw new Error(`${file}: not an STL file: neither binary (84 + 50 × its triangle count bytes) nor ASCII ("solid ...")`);
  const lines = new TextDecoder().decode(bytes).split(/\r\n|\r|\n/);
  const out = [];
  let cur = null, tri = [];
  for (let i = 0; i < lines.length; i++) {
    const tok = lines[i].trim().split(/\s+/);
    if (tok[0] === 'solid') {
      cur = { name: tok.slice(1).join(' '), w: welder(), FV: [] };
      out.push(cur);
    } else if (tok[0] === 'vertex') {
      if (!cur) throw new Error(`${file}: line ${i + 1}: a vertex outside "solid"`);
      if (tok.length !== 4) throw new Error(`${file}: line ${i + 1}: a vertex has 3 coordinates, this one ${tok.length - 1}`);
      const p = [num(tok[1], file, i + 1), num(tok[2], file, i + 1), num(tok[3], file, i + 1)];
      tri.push(cur.w.at(p.join(','), p));
    } else if (tok[0] === 'endloop') {
      if (tri.length !== 3) throw new Error(`${file}: line ${i + 1}: a facet has 3 vertices, this one ${tri.length}`);
      if (tri[0] !== tri[1] && tri[1] !== tri[2] && tri[0] !== tri[2]) cur.FV.push(tri);
      tri = [];
    }
  }
  const solids = out.filter((o) => o.FV.length);
  if (!solids.length) throw new Error(`${file}: no facets: not a solid`);
  const named = solids.length > 1;
  return solids.map((o, k) => ({ name: named ? o.name || `solid ${k}` : '', V: o.w.V, FV: o.FV }));
}

// PLY: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", elements with their
// properties (scalar "property TYPE NAME" or "property list COUNTTYPE ITEMTYPE NAME"),
// "end_header", then the elements' data in order.  The vertex element's x, y, z and the face
// element's vertex_indices (or vertex_index) list make the solid; every other element and
// property is read past.
const PLY_TYPES = {
  char: ['Int8', 1], int8: ['Int8', 1], uchar: ['Uint8', 1], uint8: ['Uint8', 1],
  short: ['Int16', 2], int16: ['Int16', 2], ushort: ['Uint16', 2], uint16: ['Uint16', 2],
  int: ['Int32', 4], int32: ['Int32', 4], uint: ['Uint32', 4], uint32: ['Uint32', 4],
  float: ['Float32', 4], float32: ['Float32', 4], double: ['Float64', 8], float64: ['Float64', 8],
};

export function readPly(bytes, file) {
  // the header: ASCII lines up to "end_header"
  let end = -1;
  const probe = new TextDecoder('latin1').decode(bytes.subarray(0, Math.min(bytes.length, 65536)));
  const m = /end_header[ \t]*(\r\n|\n|\r)/.exec(probe);
  if (m) end = m.index + m[0].length;
  if (!/^ply(\r\n|\n|\r)/.test(probe) || end < 0) throw new Error(`${file}: not a PLY file ("ply" ... "end_header")`);
  const hl = probe.slice(0, end).split(/\r\n|\n|\r/);
  let format = '';
  const elements = [];
  hl.forEach((line, i) => {
    const t = line.trim().split(/\s+/);
    if (t[0] === 'format') format = t[1];
    else if (t[0] === 'element') {
      const n = Number(t[2]);
      if (!Number.isInteger(n) || n < 0) throw new Error(`${file}: line ${i + 1}: an element count '${t[2]}'`);
      elements.push({ name: t[1], count: n, props: [] });
    } else if (t[0] === 'property') {
      const el = elements[elements.length - 1];
      if (!el) throw new Error(`${file}: line ${i + 1}: a property before any element`);
      const list = t[1] === 'list';
      const types = list ? [t[2], t[3]] : [t[1]];
      for (const ty of types) if (!PLY_TYPES[ty]) throw new Error(`${file}: line ${i + 1}: unknown property type '${ty}'`);
      el.props.push(list ? { name: t[4], count: PLY_TYPES[t[2]], item: PLY_TYPES[t[3]] } : { name: t[2], type: PLY_TYPES[t[1]] });
    }
  });
  if (!['ascii', 'binary_little_endian', 'binary_big_endian'].includes(format))
    throw new Error(`${file}: PLY format '${format}': ascii, binary_little_endian or binary_big_endian`);
  const V = [], FV = [];
  const vel = elements.find((e) => e.name === 'vertex'), fel = elements.find((e) => e.name === 'face');
  if (!vel || !fel) throw new Error(`${file}: a PLY solid needs a "vertex" and a "face" element`);
  const xyz = ['x', 'y', 'z'].map((n) => vel.props.findIndex((p) => p.name === n && !p.count));
  if (xyz.some((k) => k < 0)) throw new Error(`${file}: the vertex element has no x, y, z properties`);
  const fv = fel.props.findIndex((p) => p.count && (p.name === 'vertex_indices' || p.name === 'vertex_index'));
  if (fv < 0) throw new Error(`${file}: the face element has no vertex_indices list`);
  const take = (el, row, k) => {
    if (el === vel) {
      V.push(xyz.map((j) => row[j]));
    } else if (el === fel) {
      const f = row[fv];
      if (f.length < 3) throw new Error(`${file}: face ${k}: ${f.length} vertices (3 at least)`);
      for (const v of f) if (!Number.isInteger(v) || v < 0 || v >= vel.count) throw new Error(`${file}: face ${k}: vertex index ${v} out of range (${vel.count} vertices)`);
      FV.push(f);
    }
  };
  if (format === 'ascii') {
    const tok = new TextDecoder().decode(bytes.subarray(end)).split(/\s+/).filter((x) => x);
    let q = 0;
    const next = () => {
      if (q >= tok.length) throw new Error(`${file}: the data ends early`);
      return num(tok[q++], file, `data word ${q}`);
    };
    for (const el of elements) {
      for (let k = 0; k < el.count; k++) {
        const row = el.props.map((p) => {
          if (!p.count) return next();
          const n = next(), l = [];
          for (let j = 0; j < n; j++) l.push(next());
          return l;
        });
        take(el, row, k);
      }
    }
  } else {
    const le = format === 'binary_little_endian';
    const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    let o = end;
    const read = ([t, n]) => {
      if (o + n > bytes.length) throw new Error(`${file}: the data ends early (byte ${o})`);
      const x = dv[`get${t}`](o, le);
      o += n;
      return x;
    };
    for (const el of elements) {
      for (let k = 0; k < el.count; k++) {
        const row = el.props.map((p) => {
          if (!p.count) return read(p.type);
          const n = read(p.count), l = [];
          for (let j = 0; j < n; j++) l.push(read(p.item));
          return l;
        });
        take(el, row, k);
      }
    }
  }
  if (!V.every((p) => p.every(Number.isFinite))) throw new Error(`${file}: a vertex coordinate is not a finite number`);
  if (!FV.length) throw new Error(`${file}: no faces: not a solid`);
  return { name: '', V, FV };
}

// 3MF: a zip (its central directory read from the end) whose 3D/3dmodel.model entry (or the
// first *.model) is XML: objects with a <mesh> of <vertex x y z> and <triangle v1 v2 v3>, or
// with <components>; each build <item> is a solid per mesh it reaches, with the components'
// and the item's transforms applied (as the daemon reads 3MF, api/meshio.c).  A deflated
// entry is inflated by DecompressionStream('deflate-raw').

// A 3MF transform "m00 m01 m02 m10 ... m32" (row vectors: p' = [x y z 1] M), or null.
function transform3mf(text, where) {
  if (text === null || text === undefined || text.trim() === '') return null;
  const m = text.trim().split(/\s+/).map(Number);
  if (m.length !== 12 || !m.every(Number.isFinite)) throw new Error(`${where}: transform "${text.slice(0, 80)}": expected 12 numbers`);
  return m;
}

// a, then b (either may be null).
function compose3mf(a, b) {
  if (!a) return b;
  if (!b) return a;
  const r = new Array(12);
  for (let i = 0; i < 4; i++) {
    for (let j = 0; j < 3; j++) {
      let x = i === 3 ? b[9 + j] : 0;
      for (let k = 0; k < 3; k++) x += a[3 * i + k] * b[3 * k + j];
      r[3 * i + j] = x;
    }
  }
  return r;
}
export async function read3mf(bytes, file) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let eocd = -1;
  for (let i = bytes.length - 22; i >= Math.max(0, bytes.length - 65557); i--) {
    if (dv.getUint32(i, true) === 0x06054b50) { eocd = i; break; }
  }
  if (eocd < 0) throw new Error(`${file}: not a 3MF file (not a zip archive)`);
  const entries = dv.getUint16(eocd + 10, true);
  let p = dv.getUint32(eocd + 16, true);
  const list = [];
  for (let k = 0; k < entries; k++) {
    if (p + 46 > bytes.length || dv.getUint32(p, true) !== 0x02014b50) throw new Error(`${file}: a damaged zip directory`);
    const nl = dv.getUint16(p + 28, true), xl = dv.getUint16(p + 30, true), cl = dv.getUint16(p + 32, true);
    list.push({
      name: new TextDecoder().decode(bytes.subarray(p + 46, p + 46 + nl)), method: dv.getUint16(p + 10, true),
      csize: dv.getUint32(p + 20, true), size: dv.getUint32(p + 24, true), local: dv.getUint32(p + 42, true),
    });
    p += 46 + nl + xl + cl;
  }
  const e = list.find((x) => /^\/?3D\/3dmodel\.model$/i.test(x.name)) || list.find((x) => /\.model$/i.test(x.name));
  if (!e) throw new Error(`${file}: no 3D model in this 3MF archive (no *.model entry)`);
  if (e.local + 30 > bytes.length || dv.getUint32(e.local, true) !== 0x04034b50) throw new Error(`${file}: ${e.name}: a damaged zip entry`);
  const start = e.local + 30 + dv.getUint16(e.local + 26, true) + dv.getUint16(e.local + 28, true);
  const raw = bytes.subarray(start, start + e.csize);
  let data;
  if (e.method === 0) data = raw;
  else if (e.method === 8) {
    const s = new Blob([raw]).stream().pipeThrough(new DecompressionStream('deflate-raw'));
    try {
      data = new Uint8Array(await new Response(s).arrayBuffer());
    } catch (err) {
      throw new Error(`${file}: ${e.name}: not inflated (${err.message})`);
    }
  } else throw new Error(`${file}: ${e.name}: zip method ${e.method} (stored or deflated only)`);
  const doc = new DOMParser().parseFromString(new TextDecoder().decode(data), 'application/xml');
  const bad = doc.getElementsByTagName('parsererror')[0];
  if (bad) throw new Error(`${file}: ${e.name}: not XML: ${bad.textContent.trim().split('\n')[0].slice(0, 200)}`);
  // the objects: a mesh's vertices and triangles, or components (other objects, transformed)
  const objects = new Map();
  for (const obj of doc.getElementsByTagNameNS('*', 'object')) {
    const id = obj.getAttribute('id');
    const label = obj.getAttribute('name') || `object ${id}`;
    const mesh = obj.getElementsByTagNameNS('*', 'mesh')[0];
    if (!mesh) {
      const comps = [...obj.getElementsByTagNameNS('*', 'component')].map((c) => ({
        id: c.getAttribute('objectid'), m: transform3mf(c.getAttribute('transform'), `${file}: ${label}: a component`),
      }));
      objects.set(id, { label, comps });
      continue;
    }
    const V = [...mesh.getElementsByTagNameNS('*', 'vertex')].map((v, i) => ['x', 'y', 'z'].map((a) => {
      const x = Number(v.getAttribute(a));
      if (v.getAttribute(a) === null || !Number.isFinite(x)) throw new Error(`${file}: ${label}: vertex ${i}: ${a} is not a number`);
      return x;
    }));
    const FV = [...mesh.getElementsByTagNameNS('*', 'triangle')].map((t, i) => ['v1', 'v2', 'v3'].map((a) => {
      const x = Number(t.getAttribute(a));
      if (!Number.isInteger(x) || x < 0 || x >= V.length) throw new Error(`${file}: ${label}: triangle ${i}: ${a} = ${t.getAttribute(a)} out of range (${V.length} vertices)`);
      return x;
    }));
    objects.set(id, { label, V, FV });
  }
  // what the build places: each item's object, through its components, with the transforms
  // applied (a component's, then its parent's, then the item's); a mirroring one turns the
  // triangles round.  No build: each mesh object once, as it is.
  const out = [];
  const place = (id, m, depth, where) => {
    const o = objects.get(id);
    if (!o) throw new Error(`${file}: ${where}: no object ${id}`);
    if (depth > 16) throw new Error(`${file}: ${o.label}: components nest deeper than 16`);
    if (o.comps) {
      for (const c of o.comps) place(c.id, compose3mf(c.m, m), depth + 1, o.label);
      return;
    }
    if (!o.FV.length) return;
    const V = m ? o.V.map((p) => [0, 1, 2].map((j) => p[0] * m[j] + p[1] * m[3 + j] + p[2] * m[6 + j] + m[9 + j])) : o.V;
    const det = m ? m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]) : 1;
    if (det === 0) throw new Error(`${file}: ${o.label}: a transform that flattens it`);
    out.push({ name: o.label, V, FV: det < 0 ? o.FV.map((t) => [t[0], t[2], t[1]]) : o.FV });
  };
  const items = [...doc.getElementsByTagNameNS('*', 'item')];
  if (items.length) {
    for (const it of items) place(it.getAttribute('objectid'), transform3mf(it.getAttribute('transform'), `${file}: a build item`), 0, 'build');
  } else {
    for (const [id, o] of objects) if (o.FV) place(id, null, 0, 'resources');
  }
  if (!out.length) throw new Error(`${file}: no mesh object with triangles in ${e.name}`);
  if (out.length === 1) out[0].name = '';
  return out;
}
