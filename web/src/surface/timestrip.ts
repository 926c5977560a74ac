// The time strip of a surface's singularity paths: time runs left to right, one row per
// path from its birth (white circle, or the strip's edge) to its death (black circle),
// coloured by time as the paths on the surface are (paths.ts), a square of the path's type
// colour at its start; bifurcations are diamonds between the rows of the paths they join;
// a vertical line marks the current time. A click on a bifurcation picks it (as the
// planar space-time view's click does); a click on a birth or death, or anywhere else,
// goes to that time.
import type { Analysis } from "../api";
import { BIFURCATION_COLOR, typeColor } from "../colors";
import { timeCss } from "./paths";

export class TimeStrip {
  private analysis: Analysis | undefined;
  private range: [number, number] = [0, 1];
  private time = 0;
  private selected = -1;
  private readonly ctx: CanvasRenderingContext2D;
  onPickBifurcation: (i: number) => void = () => {};
  onPickTime: (t: number, what: string) => void = () => {};

  constructor(readonly canvas: HTMLCanvasElement) {
    this.ctx = canvas.getContext("2d")!;
    canvas.addEventListener("click", (e) => this.click(e));
  }

  set(a: Analysis, range: [number, number]) {
    this.analysis = a;
    this.range = range;
    // Rows of at least 3 pixels: the strip grows with the number of paths (to 600 pixels).
    this.canvas.height = Math.max(150, Math.min(600, 32 + 6 * a.paths.length));
    this.draw();
  }
  setTime(t: number) {
    this.time = t;
    this.draw();
  }
  highlight(i: number) {
    this.selected = i;
    this.draw();
  }

  private get left() {
    return 8;
  }
  private get width() {
    return this.canvas.width - 16;
  }
  private x(t: number) {
    return this.left + ((t - this.range[0]) / (this.range[1] - this.range[0] || 1)) * this.width;
  }
  private rowHeight() {
    const n = Math.max(1, this.analysis?.paths.length ?? 1);
    return Math.max(3, Math.min(14, (this.canvas.height - 24) / n));
  }
  private y(row: number) {
    return 8 + (row + 0.5) * this.rowHeight();
  }

  // Canvas position of bifurcation i (for the tests and the click).
  bifurcationAt(i: number): [number, number] | undefined {
    const a = this.analysis;
    const b = a?.bifurcations[i];
    if (!a || !b) return undefined;
    const rows = b.paths.map((id) => a.paths.findIndex((p) => p.id === id)).filter((r) => r >= 0);
    const row = rows.length ? rows.reduce((s, r) => s + r, 0) / rows.length : (a.paths.length - 1) / 2;
    return [this.x(b.t), this.y(row)];
  }

  private ends(): { x: number; y: number; t: number; what: string }[] {
    const a = this.analysis;
    const out: { x: number; y: number; t: number; what: string }[] = [];
    const eps = 1e-6 * (this.range[1] - this.range[0] || 1);
    a?.paths.forEach((p, row) => {
      if (p.birth > this.range[0] + eps) out.push({ x: this.x(p.birth), y: this.y(row), t: p.birth, what: `birth of path ${p.id} (${p.type})` });
      if (p.death < this.range[1] - eps) out.push({ x: this.x(p.death), y: this.y(row), t: p.death, what: `death of path ${p.id} (${p.type})` });
    });
    return out;
  }

  private draw() {
    const c = this.ctx;
    const { width: W, height: H } = this.canvas;
    c.fillStyle = "#fff";
    c.fillRect(0, 0, W, H);
    const a = this.analysis;
    if (!a) return;
    const h = this.rowHeight();
    a.paths.forEach((p, row) => {
      const y = this.y(row);
      const x0 = this.x(p.birth);
      const x1 = this.x(p.death);
      const n = Math.max(1, Math.ceil((x1 - x0) / 3));
      c.lineWidth = Math.max(2, h * 0.6);
      for (let k = 0; k < n; ++k) {
        const u0 = x0 + ((x1 - x0) * k) / n;
        const u1 = x0 + ((x1 - x0) * (k + 1)) / n;
        c.strokeStyle = timeCss((u0 + u1) / 2 / this.width - this.left / this.width);
        c.beginPath();
        c.moveTo(u0, y);
        c.lineTo(u1 + 0.5, y);
        c.stroke();
      }
      c.fillStyle = typeColor(p.type);
      c.fillRect(x0 - 3, y - 3, 6, 6);
    });
    for (const e of this.ends()) {
      c.fillStyle = e.what.startsWith("birth") ? "#fff" : "#000";
      c.strokeStyle = "#000";
      c.lineWidth = 1;
      c.beginPath();
      c.arc(e.x, e.y, 3.5, 0, 2 * Math.PI);
      c.fill();
      c.stroke();
    }
    a.bifurcations.forEach((_, i) => {
      const [x, y] = this.bifurcationAt(i)!;
      const r = i === this.selected ? 8 : 5.5;
      c.fillStyle = BIFURCATION_COLOR;
      c.strokeStyle = i === this.selected ? "#000" : BIFURCATION_COLOR;
      c.lineWidth = 1.5;
      c.beginPath();
      c.moveTo(x, y - r);
      c.lineTo(x + r, y);
      c.lineTo(x, y + r);
      c.lineTo(x - r, y);
      c.closePath();
      c.fill();
      c.stroke();
    });
    // The time axis: a ramp of the time colours, and the current time.
    for (let x = this.left; x < this.left + this.width; ++x) {
      c.fillStyle = timeCss((x - this.left) / this.width);
      c.fillRect(x, H - 10, 1, 8);
    }
    c.fillStyle = "#334155";
    c.font = "10px sans-serif";
    c.fillText(this.range[0].toFixed(2), this.left, H - 12);
    const end = this.range[1].toFixed(2);
    c.fillText(end, this.left + this.width - c.measureText(end).width, H - 12);
    const xt = this.x(this.time);
    c.strokeStyle = "#f97316";
    c.lineWidth = 2;
    c.beginPath();
    c.moveTo(xt, 0);
    c.lineTo(xt, H);
    c.stroke();
  }

  private click(e: MouseEvent) {
    const r = this.canvas.getBoundingClientRect();
    const x = ((e.clientX - r.left) * this.canvas.width) / r.width;
    const y = ((e.clientY - r.top) * this.canvas.height) / r.height;
    const a = this.analysis;
    if (!a) return;
    let best = -1;
    let bestD = 9;
    a.bifurcations.forEach((_, i) => {
      const [bx, by] = this.bifurcationAt(i)!;
      const d = Math.hypot(bx - x, by - y);
      if (d < bestD) [best, bestD] = [i, d];
    });
    if (best >= 0) return this.onPickBifurcation(best);
    for (const end of this.ends()) if (Math.hypot(end.x - x, end.y - y) < 7) return this.onPickTime(end.t, end.what);
    const t = this.range[0] + ((x - this.left) / this.width) * (this.range[1] - this.range[0]);
    this.onPickTime(Math.min(this.range[1], Math.max(this.range[0], t)), "time");
  }
}
