// view3d.js — a 3D complex in WebGL (three.js): one Mesh per bounded cell (userData.cell),
// one colour per cell, with the edges of its faces; orbit, zoom and pan (OrbitControls); an
// explode slider (each cell moved away from the centre); cell numbers; click a cell to pick
// it; show or hide cells.  A Boolean's result cells keep their colours, the other cells are
// drawn faint and see-through.  A Boolean's result is shown by default as one solid (mode
// 'result': one Mesh of its boundary faces, one colour, the cells hidden; a click still picks
// the result cell under it); mode 'cells' shows the cells.  Cell numbers that would overlap
// one already placed are left out.  Frames are drawn on demand only.
import {
  AmbientLight, BufferAttribute, BufferGeometry, Color, DirectionalLight, LineBasicMaterial,
  LineSegments, Mesh, MeshLambertMaterial, PerspectiveCamera, Raycaster, Scene, Vector2, Vector3,
  WebGLRenderer, DoubleSide, FrontSide, Group,
} from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { LabelBoxes } from './labels.js';

const MAX_LABELS = 400;
const RESULT_COLOUR = 0xe0893a;

let renderer = null; // one WebGL context for the page's life: browsers keep only a few

export class View3D {
  constructor(root, { onPick }) {
    this.root = root;
    this.onPick = onPick;
    root.innerHTML = '';
    if (!renderer) {
      renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    }
    this.renderer = renderer;
    root.append(renderer.domElement);
    this.labels = document.createElement('div');
    this.labels.className = 'labels3d';
    root.append(this.labels);
    this.scene = new Scene();
    this.scene.background = new Color(0xf7f7f4);
    this.camera = new PerspectiveCamera(40, 1, 0.01, 100);
    this.camera.position.set(2.6, -3.4, 2.4);
    this.camera.up.set(0, 0, 1);
    this.scene.add(new AmbientLight(0xffffff, 1.4));
    this.light = new DirectionalLight(0xffffff, 1.8);
    this.camera.add(this.light);
    this.light.position.set(1, 2, 3);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, renderer.domElement);
    this.controls.addEventListener('change', () => this.draw());
    this.meshes = [];
    this.cellsGroup = new Group();
    this.scene.add(this.cellsGroup);
    this.resultMesh = null;
    this.mode = 'result';
    this.explode = 1;
    this.showLabels = false;
    this.picked = -1;
    this.frame = 0;
    const ro = new ResizeObserver(() => this.resize());
    ro.observe(root);
    this.ro = ro;
    this.bindPick();
    this.resize();
  }

  bindPick() {
    const el = this.renderer.domElement;
    let down = null;
    this.onDown = (e) => { down = [e.clientX, e.clientY]; };
    this.onUp = (e) => {
      if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
      down = null;
      const r = el.getBoundingClientRect();
      const p = new Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
      const rc = new Raycaster();
      rc.setFromCamera(p, this.camera);
      // (the result as one solid: the result cell under the pointer, hidden as it is)
      const cand = this.showsResult() ? this.meshes.filter((m) => m.userData.result) : this.meshes.filter((m) => m.visible);
      const hits = rc.intersectObjects(cand.filter((m) => !m.userData.faint), false);
      const all = hits.length ? hits : rc.intersectObjects(cand, false);
      this.pick(all.length ? all[0].object.userData.cell : -1);
    };
    el.addEventListener('pointerdown', this.onDown);
    el.addEventListener('pointerup', this.onUp);
  }

  pick(c) {
    if (this.picked >= 0 && this.meshes[this.picked]) this.meshes[this.picked].material.emissive.setHex(0);
    this.picked = c;
    if (c >= 0 && this.meshes[c]) this.meshes[c].material.emissive.setHex(0x553300);
    this.draw();
    this.onPick(c);
  }

  showsResult() { return this.mode === 'result' && !!this.resultMesh; }

  disposeMeshes() {
    for (const m of [...this.meshes, ...(this.resultMesh ? [this.resultMesh] : [])]) {
      m.parent.remove(m);
      m.geometry.dispose();
      m.material.dispose();
      m.children.forEach((l) => { l.geometry.dispose(); l.material.dispose(); });
    }
    this.resultMesh = null;
  }

  show(model, mode = this.mode) {
    this.disposeMeshes();
    this.model = model;
    this.meshes = [];
    this.picked = -1;
    const boolean = !!model.result;
    for (let c = 0; c < model.cells; c++) {
      const g = new BufferGeometry();
      const a = 9 * model.triOff[c], b = 9 * model.triOff[c + 1];
      g.setAttribute('position', new BufferAttribute(model.pos.subarray(a, b), 3));
      g.setAttribute('normal', new BufferAttribute(model.nor.subarray(a, b), 3));
      const faint = boolean && !model.sel[c];
      const col = new Color().setHSL(((c * 137.508) % 360) / 360, 0.55, 0.6);
      const mat = new MeshLambertMaterial({
        color: faint ? 0xb8b8b8 : col, transparent: faint, opacity: faint ? 0.12 : 1,
        depthWrite: !faint, side: faint ? DoubleSide : FrontSide,
        polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
      });
      const mesh = new Mesh(g, mat);
      mesh.userData = { cell: c, faint, result: boolean && !!model.sel[c] };
      const eg = new BufferGeometry();
      eg.setAttribute('position', new BufferAttribute(model.seg.subarray(6 * model.segOff[c], 6 * model.segOff[c + 1]), 3));
      const lines = new LineSegments(eg, new LineBasicMaterial({
        color: faint ? 0x999999 : 0x333333, transparent: faint, opacity: faint ? 0.35 : 1,
      }));
      lines.raycast = () => {};
      mesh.add(lines);
      this.cellsGroup.add(mesh);
      this.meshes.push(mesh);
    }
    if (boolean && model.resPos) {
      const g = new BufferGeometry();
      g.setAttribute('position', new BufferAttribute(model.resPos, 3));
      g.setAttribute('normal', new BufferAttribute(model.resNor, 3));
      const mesh = new Mesh(g, new MeshLambertMaterial({
        color: RESULT_COLOUR, side: FrontSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
      }));
      const eg = new BufferGeometry();
      eg.setAttribute('position', new BufferAttribute(model.resSeg, 3));
      const lines = new LineSegments(eg, new LineBasicMaterial({ color: 0x5a3a1a }));
      lines.raycast = () => {};
      mesh.add(lines);
      mesh.raycast = () => {};
      mesh.userData = { resultSolid: true };
      this.scene.add(mesh);
      this.resultMesh = mesh;
    }
    this.setMode(mode);
    this.root.dataset.cells = String(model.cells);
    this.setExplode(1);
    this.controls.target.set(0, 0, 0);
    this.camera.position.set(2.6, -3.4, 2.4);
    this.controls.update();
    this.draw();
  }

  setExplode(k) {
    this.explode = k;
    const m = this.model;
    if (!m) return;
    for (let c = 0; c < m.cells; c++)
      this.meshes[c].position.set(m.centre[3 * c] * (k - 1), m.centre[3 * c + 1] * (k - 1), m.centre[3 * c + 2] * (k - 1));
    this.draw();
  }

  // 'result' (the result as one solid, when there is one) or 'cells'
  setMode(mode) {
    this.mode = mode;
    const r = this.showsResult();
    this.cellsGroup.visible = !r;
    if (this.resultMesh) this.resultMesh.visible = r;
    this.root.dataset.mode = r ? 'result' : 'cells';
    this.draw();
  }

  setVisible(c, on) {
    if (this.meshes[c]) this.meshes[c].visible = on;
    this.draw();
  }

  setLabels(on) {
    this.showLabels = on;
    this.draw();
  }

  resize() {
    const w = this.root.clientWidth || 1, h = this.root.clientHeight || 1;
    this.renderer.setSize(w, h, false);
    this.renderer.domElement.style.width = '100%';
    this.renderer.domElement.style.height = '100%';
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.draw();
  }

  // a frame at the next animation frame (one, however many changes asked for it)
  draw() {
    if (this.frame) return;
    this.frame = requestAnimationFrame(() => {
      this.frame = 0;
      this.renderer.render(this.scene, this.camera);
      this.drawLabels();
      this.root.dataset.frames = String(Number(this.root.dataset.frames || 0) + 1);
    });
  }

  // numbers at the cells' centres (spans placed through the CSSOM: the page's
  // Content-Security-Policy allows no inline style)
  drawLabels() {
    const m = this.model;
    const spans = this.labels.children;
    let n = 0;
    const boxes = new LabelBoxes();
    this.skipped = 0;
    if (this.showLabels && m) {
      const w = this.root.clientWidth, h = this.root.clientHeight, v = new Vector3();
      const res = this.showsResult();
      for (let c = 0; c < m.cells && n < MAX_LABELS; c++) {
        const mesh = this.meshes[c];
        if (res ? !mesh.userData.result : !mesh.visible) continue;
        v.set(m.centre[3 * c], m.centre[3 * c + 1], m.centre[3 * c + 2]).add(mesh.position).project(this.camera);
        if (v.z > 1 || Math.abs(v.x) > 1 || Math.abs(v.y) > 1) continue;
        const x = ((v.x + 1) / 2) * w, y = ((1 - v.y) / 2) * h;
        // the span's box (12 px bold digits, 3 px padding): left out where it would overlap
        const bw = 7.5 * String(c).length + 6, bh = 16;
        if (!boxes.place(x - bw / 2, y - bh / 2, bw, bh)) { this.skipped++; continue; }
        const s = n < spans.length ? spans[n] : this.labels.appendChild(document.createElement('span'));
        s.textContent = String(c);
        s.className = mesh.userData.faint ? 'faint' : '';
        s.style.left = `${x.toFixed(0)}px`;
        s.style.top = `${y.toFixed(0)}px`;
        n++;
      }
    }
    this.placed = boxes.list;
    while (spans.length > n) spans[spans.length - 1].remove();
  }

  destroy() {
    this.ro.disconnect();
    this.controls.dispose();
    const el = this.renderer.domElement;
    el.removeEventListener('pointerdown', this.onDown);
    el.removeEventListener('pointerup', this.onUp);
    this.disposeMeshes();
    this.meshes = [];
    this.root.innerHTML = '';
  }
}
