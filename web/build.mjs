// build.mjs OUTDIR — builds the page cellard serves at / into OUTDIR (run by the Makefile
// through scripts/web-build.sh, which runs `npm ci` first when web/node_modules is missing):
//   - src/worker.js and src/main.js bundled by esbuild (ES modules, minified, tree-shaken:
//     only the parts of three.js the page imports), style.css minified;
//   - every file of examples/ copied, with a list of them (examples.json) for the picker;
//   - every asset named by its content (app-0123456789.js): the names change exactly when the
//     bytes do, so cellard serves them as immutable; index.html (not renamed, revalidated)
//     names them;
//   - every URL the page names (in index.html, examples.json, the bundles) relative to the
//     page ("assets/app-0123456789.js"): the service may be mounted under a sub-path behind a
//     proxy (/cellar/); the routes cellard serves them at are absolute ("/assets/...");
//   - OUTDIR/assets.list: one line per asset, "URL<TAB>FILE<TAB>MEDIA TYPE<TAB>CACHE", which
//     scripts/web-embed.sh turns into the C table cellard serves from.
import { createHash } from 'node:crypto';
import { mkdirSync, readFileSync, readdirSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { basename, dirname, extname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as esbuild from 'esbuild';

const web = dirname(fileURLToPath(import.meta.url));
const top = resolve(web, '..');
const out = resolve(process.argv[2] || join(top, 'build/web'));
const IMMUTABLE = 'public, max-age=31536000, immutable';
const REVALIDATE = 'no-cache';
const types = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8', '.json': 'application/json', '.svg': 'image/svg+xml',
  '.obj': 'model/obj', '.off': 'text/plain; charset=utf-8',
  '.geojson': 'application/geo+json', '.txt': 'text/plain; charset=utf-8',
};
const typeOf = (name) => types[extname(name).toLowerCase()] || 'application/octet-stream';

rmSync(join(out, 'assets.list'), { force: true }); // written last: only a finished build has one
rmSync(join(out, 'assets'), { recursive: true, force: true });
mkdirSync(join(out, 'assets/examples'), { recursive: true });
const list = [];
const sizes = {};

// Writes bytes under assets/ with their content hash in the name; returns its URL relative to
// the page (the route in the list: "/" and that).
function put(name, bytes, sub = '') {
  const h = createHash('sha256').update(bytes).digest('hex').slice(0, 10);
  const ext = extname(name);
  const file = join('assets', sub, `${basename(name, ext)}-${h}${ext}`);
  writeFileSync(join(out, file), bytes);
  const url = file.split('\\').join('/');
  list.push(['/' + url, file, typeOf(name), IMMUTABLE]);
  sizes[sub ? `${sub}/${name}` : name] = bytes.length;
  return url;
}

// the examples, and the picker's list: each file, then all the solids files together, then all
// the GeoJSON files together (layers)
const exdir = join(top, 'examples');
const files = readdirSync(exdir).filter((f) => statSync(join(exdir, f)).isFile()).sort();
for (const f of files)  // a URL and a C string as they are
  if (!/^[A-Za-z0-9][A-Za-z0-9._-]*$/.test(f)) throw new Error(`examples/${f}: a name of [A-Za-z0-9._-] only`);
const urls = {};
for (const f of files) urls[f] = put(f, readFileSync(join(exdir, f)), 'examples');
const examples = files.map((f) => ({ name: f, files: [{ name: f, url: urls[f] }] }));
const solids = files.filter((f) => /\.(obj|off|stl|ply|3mf)$/i.test(f));
if (solids.length > 1)
  examples.push({ name: solids.join(' + '), files: solids.map((f) => ({ name: f, url: urls[f] })) });
// the GeoJSON files together: their layers overlaid
const layers = files.filter((f) => /\.geojson$/i.test(f));
if (layers.length > 1)
  examples.push({ name: layers.join(' + '), files: layers.map((f) => ({ name: f, url: urls[f] })) });
const examplesUrl = put('examples.json', Buffer.from(JSON.stringify(examples)));

const common = {
  bundle: true, format: 'esm', minify: true, write: false, target: ['es2022'],
  legalComments: 'none', logLevel: 'warning', absWorkingDir: web,
};
const worker = await esbuild.build({ ...common, entryPoints: ['src/worker.js'] });
const workerUrl = put('worker.js', Buffer.from(worker.outputFiles[0].contents));
const app = await esbuild.build({
  ...common, entryPoints: ['src/main.js'], metafile: true,
  define: { __WORKER_URL__: JSON.stringify(workerUrl), __EXAMPLES_URL__: JSON.stringify(examplesUrl) },
});
const appUrl = put('app.js', Buffer.from(app.outputFiles[0].contents));
const css = await esbuild.transform(readFileSync(join(web, 'style.css'), 'utf8'),
  { loader: 'css', minify: true });
const cssUrl = put('style.css', Buffer.from(css.code));

let html = readFileSync(join(web, 'index.html'), 'utf8');
for (const [k, v] of [['%APP%', appUrl], ['%CSS%', cssUrl]]) {
  if (!html.includes(k)) throw new Error(`web/index.html lacks ${k}`);
  html = html.replaceAll(k, v);
}
writeFileSync(join(out, 'index.html'), html);
list.unshift(['/', 'index.html', typeOf('index.html'), REVALIDATE]);
sizes['index.html'] = Buffer.byteLength(html);
writeFileSync(join(out, 'assets.list'), list.map((l) => l.join('\t')).join('\n') + '\n');

// what three.js costs in the bundle (its share of the minified output)
let three = 0;
for (const o of Object.values(app.metafile.outputs))
  for (const [input, v] of Object.entries(o.inputs))
    if (input.includes('node_modules/three/')) three += v.bytesInOutput;
const page = sizes['index.html'] + sizes['app.js'] + sizes['style.css'] + sizes['worker.js'];
writeFileSync(join(out, 'sizes.json'), JSON.stringify({ ...sizes, three_in_app: three, page }, null, 1) + '\n');
console.error(`web: app.js ${sizes['app.js']} B (three.js ${three} B of it), worker.js ` +
  `${sizes['worker.js']} B, style.css ${sizes['style.css']} B, index.html ` +
  `${sizes['index.html']} B; the page ${page} B; ${files.length} examples`);
