// input.js — files to requests (README, "Requests"):
//   an SVG drawing      -> {"kind": "svg", "svg": TEXT, "options": {"y_up": true}}
//   OBJ and OFF files   -> {"kind": "solids", "solids": [...]}: a solid per file (as
//                          `cellar solids A.obj B.off` reads them), and per object ("o") of an
//                          OBJ file that holds several
//   a JSON request      -> sent as it is (an object with a "kind")
//   GeoJSON             -> {"kind": "polygons", "polygons": [...], "op": "union"}: a polygon
//                          per Polygon or MultiPolygon feature (a .geojson file, or JSON whose
//                          "type" is GeoJSON's)
// Each function returns {request, label, names} (names: the inputs' names, for membership) or
// throws an Error whose message names the file and the line.

const GEOJSON_TYPES = new Set(['FeatureCollection', 'Feature', 'Polygon', 'MultiPolygon',
  'GeometryCollection']);

export function kindOf(name) {
  const m = /\.([a-z0-9]+)$/i.exec(name);
  const ext = m ? m[1].toLowerCase() : '';
  if (ext === 'svg') return 'svg';
  if (ext === 'obj' || ext === 'off') return ext;
  if (ext === 'geojson') return 'geojson';
  if (ext === 'json') return 'json';
  return '';
}

// files: [{name, text}]
export function requestFromFiles(files) {
  if (!files.length) throw new Error('no file');
  const kinds = files.map((f) => {
    const k = kindOf(f.name);
    if (!k) throw new Error(`${f.name}: not an SVG, OBJ, OFF, JSON or GeoJSON file (by its extension)`);
    return k;
  });
  if (kinds.every((k) => k === 'obj' || k === 'off')) return solidsRequest(files);
  if (files.length > 1)
    throw new Error('one SVG, JSON or GeoJSON file at a time (several files: OBJ or OFF, a solid each)');
  const [f] = files;
  if (kinds[0] === 'svg') {
    if (!/<svg[\s>]/.test(f.text)) throw new Error(`${f.name}: no <svg> element: not an SVG drawing`);
    return { request: { kind: 'svg', svg: f.text, options: { y_up: true } }, label: f.name, names: [] };
  }
  let doc;
  try {
    doc = JSON.parse(f.text);
  } catch (e) {
    throw new Error(`${f.name}: not JSON: ${e.message}`);
  }
  if (kinds[0] === 'geojson' || (doc && typeof doc === 'object' && GEOJSON_TYPES.has(doc.type) && !doc.kind))
    return geojsonRequest(doc, f.name);
  if (!doc || typeof doc !== 'object' || Array.isArray(doc) || typeof doc.kind !== 'string')
    throw new Error(`${f.name}: not a request (a JSON object with a "kind": lines, svg, polygons, solids) nor GeoJSON`);
  return { request: doc, label: f.name, names: namesOf(doc) };
}

// The inputs' names of a request, for membership (polygon i, solid i).
export function namesOf(req) {
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

export function geojsonRequest(doc, name) {
  const polygons = [], names = [];
  let skipped = 0;
  const add = (g, label) => {
    if (!g || typeof g !== 'object') { skipped++; return; }
    if (g.type === 'Polygon' || g.type === 'MultiPolygon') {
      polygons.push(g);
      names.push(label);
    } else if (g.type === 'GeometryCollection' && Array.isArray(g.geometries)) {
      g.geometries.forEach((x, j) => add(x, `${label}.${j}`));
    } else skipped++;
  };
  if (doc.type === 'FeatureCollection') {
    if (!Array.isArray(doc.features)) throw new Error(`${name}: a FeatureCollection without "features"`);
    doc.features.forEach((ft, i) => add(ft && ft.geometry, featureName(ft, i)));
  } else if (doc.type === 'Feature') add(doc.geometry, featureName(doc, 0));
  else add(doc, 'geometry 0');
  if (!polygons.length)
    throw new Error(`${name}: no Polygon or MultiPolygon in this GeoJSON (${skipped} other geometries)`);
  const request = { kind: 'polygons', polygons, op: 'union' };
  const note = skipped ? ` (${skipped} feature${skipped > 1 ? 's' : ''} without a polygon left out)` : '';
  return { request, label: `${name}: ${polygons.length} polygons${note}`, names };
}

export function solidsRequest(files) {
  const solids = [], names = [];
  for (const f of files) {
    const parts = kindOf(f.name) === 'off' ? [readOff(f.text, f.name)] : readObj(f.text, f.name);
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
