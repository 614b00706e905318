// labels.js — numbers on a picture without a pile: LabelBoxes places screen boxes (x, y, w, h
// in CSS pixels) one after the other and refuses a box that overlaps one already placed (a
// grid of 32-pixel buckets finds the neighbours), so that the labels of many small faces or
// cells never stack into one unreadable column.  `list` holds the boxes placed.
const CELL = 32;

export class LabelBoxes {
  constructor() {
    this.grid = new Map();
    this.list = [];
  }

  // places the box and returns true, or returns false when it overlaps a placed one
  place(x, y, w, h) {
    const i0 = Math.floor(x / CELL), i1 = Math.floor((x + w) / CELL);
    const j0 = Math.floor(y / CELL), j1 = Math.floor((y + h) / CELL);
    for (let j = j0; j <= j1; j++) {
      for (let i = i0; i <= i1; i++) {
        const b = this.grid.get(`${i},${j}`);
        if (!b) continue;
        for (const o of b) if (x < o[0] + o[2] && o[0] < x + w && y < o[1] + o[3] && o[1] < y + h) return false;
      }
    }
    const box = [x, y, w, h];
    for (let j = j0; j <= j1; j++) {
      for (let i = i0; i <= i1; i++) {
        const k = `${i},${j}`;
        if (!this.grid.has(k)) this.grid.set(k, []);
        this.grid.get(k).push(box);
      }
    }
    this.list.push(box);
    return true;
  }
}
