// view2d.js — a 2D complex on a canvas.  The faces are filled in BUCKETS colours, each colour
// one Path2D holding its faces' cycles (outer cycles counter-clockwise, holes clockwise, as the
// result has them: the non-zero rule cuts the holes out and still fills a face lying inside
// another's hole), then stroked (the edges, but where the faces are specks on the screen),
// dangling edges and a Boolean's result outline on top.  So a frame of 100 000 faces is a few
// dozen fills, not 100 000 elements.  A Boolean's result faces keep their colours, the others
// are greyed.
//   Zoom with the wheel at the cursor, pan by dragging, double-click to fit; hover a face (a
// grid of the faces' boxes, then an exact even-odd test) for its id, area and membership;
// face and vertex numbers of what is in view (a number whose box would overlap one already
// placed is left out: the labels of small faces do not pile up); explode.
//   A Boolean's result is shown by default as one region (mode 'result': its faces filled in
// one colour, without the edges between them, its outline on top, the other faces grey);
// mode 'cells' shows every face in its own colour.
// The paths are made by the worker (worker.js, paths2) as SVG path data.
// For the tests: `drawn` = {faces, selected, dangling} counts what the current paths hold
// (faces filled, faces filled as the result, dangling edges), `drawnSelected()` the result's, facePixel(f) where face f's
// number goes and the colour it is filled with.
const BUCKETS = 48;
const MAX_LABELS = 1500;
const GREY = '#e1e3e6';
const REGION = '#f0a868';

export function faceColour(f) {
  const b = f % BUCKETS;
  return `hsl(${((b * 137.508) % 360).toFixed(1)} 62% ${70 + (b % 3) * 5}%)`;
}

import { LabelBoxes } from './labels.js';

export class View2D {
  constructor(root, { onHover, onView, explodePaths }) {
    this.root = root;
    this.explodePaths = explodePaths;
    this.onHover = onHover;
    this.onView = onView || (() => {});
    this.model = null;
    this.explode = 1;
    this.numbers = { faces: false, vertices: false };
    this.hovered = -1;
    this.mode = 'result';
    this.drawn = { faces: 0, selected: 0 };
    root.innerHTML = '';
    this.canvas = document.createElement('canvas');
    this.canvas.className = 'view2d';
    this.over = document.createElement('canvas'); // the hovered face
    this.over.className = 'view2d over';
    this.note = document.createElement('div');
    this.note.className = 'viewnote';
    root.append(this.canvas, this.over, this.note);
    // a canvas in memory, drawn by the CPU: a GPU canvas tessellates these large paths again
    // at every frame (and, in software without a GPU, takes seconds)
    this.ctx = this.canvas.getContext('2d', { willReadFrequently: true });
    this.octx = this.over.getContext('2d');
    this.frame = 0;
    this.ro = new ResizeObserver(() => this.resize());
    this.ro.observe(root);
    this.bindEvents();
  }

  // ---- paths ----------------------------------------------------------------------------

  // the cycles of face f into path p, moved by (dx, dy)
  addFace(p, f, dx, dy) {
    const m = this.model, { faceCyc, cycOff, cyc, vxy } = m;
    for (let k = faceCyc[f]; k < faceCyc[f + 1]; k++) {
      const a = cycOff[k], b = cycOff[k + 1];
      p.moveTo(vxy[2 * cyc[a]] + dx, vxy[2 * cyc[a] + 1] + dy);
      for (let i = a + 1; i < b; i++) p.lineTo(vxy[2 * cyc[i]] + dx, vxy[2 * cyc[i] + 1] + dy);
      p.closePath();
    }
  }

  offset(f) {
    const m = this.model, t = this.explode - 1;
    return t ? [(m.cx[f] - m.width / 2) * t, (m.cy[f] - m.height / 2) * t] : [0, 0];
  }

  // Path2D objects of the worker's path data (paths2 in worker.js)
  setPaths(pd) {
    const mk = (d) => (d ? new Path2D(d) : null);
    this.paths = {
      fills: pd.fills.map(mk), grey: mk(pd.grey), region: mk(pd.region), dangling: mk(pd.dangling), outline: mk(pd.outline),
    };
    this.drawn = { faces: pd.faces, selected: pd.selected, dangling: pd.dangling_edges };
    this.canvas.dataset.faces = String(pd.faces);
    this.canvas.dataset.selected = String(pd.selected);
  }

  drawnSelected() {
    const m = this.model, out = [];
    if (m && m.result) for (let f = 0; f < m.faces; f++) if (m.sel[f]) out.push(f);
    return out;
  }

  // ---- the view -------------------------------------------------------------------------

  // 'result' (a Boolean's result as one region) or 'cells'
  setMode(mode) {
    this.mode = mode;
    this.root.dataset.mode = this.showsResult() ? 'result' : 'cells';
    this.draw();
  }

  showsResult() { return this.mode === 'result' && !!(this.model && this.model.result); }

  show(model, mode = this.mode) {
    this.model = model;
    this.mode = mode;
    this.root.dataset.mode = this.showsResult() ? 'result' : 'cells';
    this.hovered = -1;
    this.onHover(-1, null);
    this.explode = 1;
    this.setPaths(model.paths);
    model.paths = null;
    // the mean face's side in view units: edges are not stroked where faces are specks
    let a = 0;
    for (let f = 0; f < model.faces; f++) a += model.box[4 * f + 2] - model.box[4 * f];
    this.faceSize = model.faces ? a / model.faces : 0;
    this.fit();
  }

  resize() {
    const dpr = window.devicePixelRatio || 1;
    const w = this.root.clientWidth || 1, h = this.root.clientHeight || 1;
    for (const c of [this.canvas, this.over]) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    this.dpr = dpr;
    if (this.model && !this.k) this.fit();
    else this.draw();
  }

  // the whole drawing, with a margin: k screen pixels a view unit, (tx, ty) the screen
  // position of the view's origin
  fit() {
    const m = this.model;
    if (!m) return;
    const w = this.root.clientWidth || 1, h = this.root.clientHeight || 1;
    const mw = Math.max(m.width, 1e-9), mh = Math.max(m.height, 1e-9);
    this.k = Math.min((w * 0.94) / mw, (h * 0.94) / mh);
    if (!Number.isFinite(this.k) || this.k <= 0) this.k = (0.94 * Math.min(w, h)) / 1e6;
    this.tx = (w - m.width * this.k) / 2;
    this.ty = (h - m.height * this.k) / 2;
    this.draw();
  }

  zoomAt(z, sx, sy) {
    const k = Math.min(Math.max(this.k * z, 1e-9), 1e6);
    z = k / this.k;
    this.tx = sx - (sx - this.tx) * z;
    this.ty = sy - (sy - this.ty) * z;
    this.k = k;
    this.draw();
  }

  zoom(z) {
    this.zoomAt(z, this.root.clientWidth / 2, this.root.clientHeight / 2);
  }

  toView(sx, sy) { return [(sx - this.tx) / this.k, (sy - this.ty) / this.k]; }

  toWorld(x, y) {
    const w = this.model.world;
    return [w.minx + x / w.s, w.flipY ? w.maxy - y / w.s : w.miny + y / w.s];
  }

  draw() {
    if (this.frame || !this.model) return;
    this.frame = requestAnimationFrame(() => {
      this.frame = 0;
      this.render();
    });
  }

  render() {
    const m = this.model, ctx = this.ctx, d = this.dpr || 1, k = this.k, p = this.paths;
    if (!m || !p) return;
    const t0 = performance.now();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.setTransform(d * k, 0, 0, d * k, d * this.tx, d * this.ty);
    const region = this.showsResult();
    if (p.grey) {
      ctx.fillStyle = GREY;
      ctx.fill(p.grey);
    }
    if (region) {
      if (p.region) {
        ctx.fillStyle = REGION;
        ctx.fill(p.region);
      }
    } else {
      for (let b = 0; b < BUCKETS; b++) {
        if (!p.fills[b]) continue;
        ctx.fillStyle = faceColour(b);
        ctx.fill(p.fills[b]);
      }
    }
    ctx.lineJoin = 'round';
    if (this.faceSize * k >= 8) { // the outlines: where faces are specks, only darkness
      ctx.lineWidth = 0.7 / k;
      ctx.strokeStyle = '#a3a9b2';
      if (p.grey) ctx.stroke(p.grey);
      ctx.strokeStyle = '#39414c';
      if (!region) {
        for (const f of p.fills) if (f) ctx.stroke(f);
      } else if (this.explode !== 1 && p.region) ctx.stroke(p.region); // exploded: no outline
    }
    if (p.dangling) {
      ctx.strokeStyle = '#c0392b';
      ctx.lineWidth = 1.5 / k;
      ctx.stroke(p.dangling);
    }
    if (p.outline) {
      ctx.strokeStyle = '#e8730c';
      ctx.lineWidth = 3 / k;
      ctx.stroke(p.outline);
    }
    this.renderLabels();
    // the face under the pointer may have changed with the view
    if (this.pointer && !this.dragging) {
      const [x, y] = this.toView(...this.pointer);
      const f = this.faceAt(x, y);
      if (f !== this.hovered) {
        this.hovered = f;
        this.onHover(f, this.toWorld(x, y));
      }
    }
    this.renderHover();
    this.lastFrameMs = performance.now() - t0;
    this.canvas.dataset.frames = String(Number(this.canvas.dataset.frames || 0) + 1);
    this.onView();
  }

  // face and vertex numbers of what lies in view, at most MAX_LABELS of each, in screen space
  renderLabels() {
    const m = this.model, ctx = this.ctx, d = this.dpr || 1;
    this.note.textContent = '';
    if (!this.numbers.faces && !this.numbers.vertices) return;
    const w = this.root.clientWidth, h = this.root.clientHeight;
    ctx.setTransform(d, 0, 0, d, 0, 0);
    ctx.font = '12px system-ui, sans-serif';
    ctx.lineWidth = 3;
    ctx.strokeStyle = 'rgba(255,255,255,0.85)';
    let over = 0;
    const boxes = new LabelBoxes();
    this.faceLabels = [];
    // a number whose box (its width, 14 px high) overlaps one already placed is left out
    const put = (x, y, text, colour, left) => {
      const tw = ctx.measureText(text).width + 2, th = 14;
      const bx = left ? x : x - tw / 2, by = left ? y - th : y - th / 2;
      if (!boxes.place(bx, by, tw, th)) return false;
      ctx.strokeText(text, x, y);
      ctx.fillStyle = colour;
      ctx.fillText(text, x, y);
      return true;
    };
    if (this.numbers.faces) {
      ctx.textAlign = 'center';
      ctx.textBaseline = 'middle';
      let n = 0;
      for (let f = 0; f < m.faces; f++) {
        const [dx, dy] = this.offset(f);
        const x = this.tx + (m.lx[f] + dx) * this.k, y = this.ty + (m.ly[f] + dy) * this.k;
        if (x < 0 || x > w || y < 0 || y > h) continue;
        if (n >= MAX_LABELS) { over++; continue; }
        if (put(x, y, String(f), '#111', false)) { n++; this.faceLabels.push(f); } else over++;
      }
    }
    if (this.numbers.vertices && this.explode === 1) {
      ctx.textAlign = 'left';
      ctx.textBaseline = 'bottom';
      let n = 0;
      for (let v = 0; v < m.vertices; v++) {
        const x = this.tx + m.vxy[2 * v] * this.k, y = this.ty + m.vxy[2 * v + 1] * this.k;
        if (x < 0 || x > w || y < 0 || y > h) continue;
        if (n >= MAX_LABELS) { over++; continue; }
        ctx.fillStyle = '#1f4e9c';
        ctx.fillRect(x - 1.5, y - 1.5, 3, 3);
        if (put(x + 3, y - 2, String(v), '#1f4e9c', true)) n++; else over++;
      }
    }
    this.placed = boxes.list;
    this.skipped = over;
    if (over) this.note.textContent = `${over} more numbers in view (left out where they would overlap): zoom in to see them`;
    else if (this.numbers.vertices && this.explode !== 1) this.note.textContent = 'vertex numbers: not while exploded';
  }

  renderHover() {
    const ctx = this.octx, d = this.dpr || 1, f = this.hovered;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.over.width, this.over.height);
    if (f < 0 || !this.model) return;
    const p = new Path2D();
    const [dx, dy] = this.offset(f);
    this.addFace(p, f, dx, dy);
    ctx.setTransform(d * this.k, 0, 0, d * this.k, d * this.tx, d * this.ty);
    ctx.fillStyle = 'rgba(255,255,255,0.25)';
    ctx.fill(p);
    ctx.strokeStyle = '#000';
    ctx.lineWidth = 2.5 / this.k;
    ctx.stroke(p);
  }

  // ---- hover ----------------------------------------------------------------------------

  // the face under view point (x, y), or -1 (exploded: each face at its offset)
  faceAt(x, y) {
    const m = this.model;
    if (!m || !m.faces) return -1;
    const hit = (f) => {
      const [dx, dy] = this.offset(f);
      const px = x - dx, py = y - dy, b = m.box;
      if (px < b[4 * f] || px > b[4 * f + 2] || py < b[4 * f + 1] || py > b[4 * f + 3]) return false;
      let inn = false;
      const { faceCyc, cycOff, cyc, vxy } = m;
      for (let k = faceCyc[f]; k < faceCyc[f + 1]; k++) {
        const a = cycOff[k], n = cycOff[k + 1] - a;
        for (let i = 0, j = n - 1; i < n; j = i++) {
          const xi = vxy[2 * cyc[a + i]], yi = vxy[2 * cyc[a + i] + 1];
          const xj = vxy[2 * cyc[a + j]], yj = vxy[2 * cyc[a + j] + 1];
          if ((yi > py) !== (yj > py) && px < ((xj - xi) * (py - yi)) / (yj - yi) + xi) inn = !inn;
        }
      }
      return inn;
    };
    if (this.explode !== 1) { // faces moved: no grid
      for (let f = m.faces - 1; f >= 0; f--) if (hit(f)) return f;
      return -1;
    }
    const g = m.grid;
    const i = Math.floor(x / g.cw), j = Math.floor(y / g.ch);
    if (i < 0 || j < 0 || i >= g.gw || j >= g.gh) return -1;
    const c = j * g.gw + i;
    for (let q = m.gridOff[c]; q < m.gridOff[c + 1]; q++) if (hit(m.gridIds[q])) return m.gridIds[q];
    return -1;
  }

  // where face f's number goes on the screen (CSS pixels from the canvas' corner) and the
  // colour it is filled with
  facePixel(f) {
    const m = this.model;
    const [dx, dy] = this.offset(f);
    const on = !m.result || m.sel[f];
    const fill = !on ? GREY : this.showsResult() ? REGION : faceColour(f);
    return { x: this.tx + (m.lx[f] + dx) * this.k, y: this.ty + (m.ly[f] + dy) * this.k, fill, selected: !!(m.result && m.sel[f]) };
  }

  bindEvents() {
    const el = this.over;
    let drag = null;
    el.addEventListener('wheel', (e) => {
      if (!this.model) return;
      e.preventDefault();
      const r = el.getBoundingClientRect();
      this.zoomAt(Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)), e.clientX - r.left, e.clientY - r.top);
    }, { passive: false });
    el.addEventListener('pointerdown', (e) => {
      if (!this.model || e.button !== 0) return;
      drag = { x: e.clientX, y: e.clientY, tx: this.tx, ty: this.ty, id: e.pointerId };
      this.dragging = true;
      el.setPointerCapture(e.pointerId);
      el.classList.add('dragging');
    });
    el.addEventListener('pointermove', (e) => {
      if (drag && e.pointerId === drag.id) {
        this.tx = drag.tx + e.clientX - drag.x;
        this.ty = drag.ty + e.clientY - drag.y;
        this.draw();
        return;
      }
      if (!this.model) return;
      const r = el.getBoundingClientRect();
      this.pointer = [e.clientX - r.left, e.clientY - r.top];
      const [x, y] = this.toView(...this.pointer);
      this.hover(this.faceAt(x, y), this.toWorld(x, y));
    });
    const up = (e) => {
      if (!drag || e.pointerId !== drag.id) return;
      drag = null;
      this.dragging = false;
      el.classList.remove('dragging');
    };
    el.addEventListener('pointerup', up);
    el.addEventListener('pointercancel', up);
    el.addEventListener('pointerleave', () => {
      this.pointer = null;
      if (!drag) this.hover(-1, null);
    });
    el.addEventListener('dblclick', () => this.fit());
  }

  hover(f, at) {
    if (f !== this.hovered) {
      this.hovered = f;
      this.renderHover();
    }
    this.onHover(f, at);
  }

  // explode: every face moved away from the drawing's centre by (k - 1) times its distance
  // (the worker makes the paths, one request at a time: a slider moved meanwhile asks again
  // for where it rests)
  async setExplode(k) {
    this.wantExplode = k;
    if (this.exploding || !this.model) return;
    this.exploding = true;
    const model = this.model;
    try {
      while (this.wantExplode !== undefined && model === this.model) {
        const kk = this.wantExplode;
        this.wantExplode = undefined;
        const pd = await this.explodePaths(kk);
        if (model !== this.model) break;
        this.explode = kk;
        this.setPaths(pd);
        this.draw();
      }
    } finally {
      this.exploding = false;
    }
  }

  setNumbers(n) {
    this.numbers = n;
    this.draw();
  }

  destroy() {
    cancelAnimationFrame(this.frame);
    this.ro.disconnect();
    this.root.innerHTML = '';
    this.model = null;
  }
}
