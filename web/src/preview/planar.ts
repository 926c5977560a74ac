// The planar grid's moving preview: texture advection (advect.ts) on a square picture of
// the grid, stepped by the page's ticker (ticker.ts) and drawn under the design; and the
// arrows of the planar glyph view.
import { sample, type GridField } from "../lic";
import type { View } from "../view";
import { Advection, gridFlow, type PixelFlow } from "./advect";

export class PlanarPreview {
  readonly canvas: HTMLCanvasElement;
  private readonly ctx: CanvasRenderingContext2D;
  private readonly advection: Advection;
  private readonly image: ImageData;
  private readonly grey: Uint8Array;
  private flow: PixelFlow | undefined;
  private key: unknown;

  constructor(readonly size = 256) {
    this.canvas = document.createElement("canvas");
    this.canvas.width = size;
    this.canvas.height = size;
    this.ctx = this.canvas.getContext("2d")!;
    this.advection = new Advection(size, size, { seed: 7 });
    this.image = this.ctx.createImageData(size, size);
    this.grey = new Uint8Array(size * size);
    this.draw();
  }

  // The field to follow; `key` names it (the frame object): the flow is computed again
  // only when it changes.
  setField(field: GridField, key: unknown) {
    if (key === this.key) return;
    this.key = key;
    this.flow = gridFlow(field, this.size, this.size, 1.5);
  }

  get hasField(): boolean {
    return this.flow !== undefined;
  }

  step(n = 1) {
    if (!this.flow) return;
    for (let k = 0; k < n; ++k) this.advection.step(this.flow);
    this.draw();
  }

  private draw() {
    if (this.flow) this.advection.shown(this.flow, 8, this.grey);
    else this.advection.grey(undefined, this.grey);
    const d = this.image.data;
    for (let k = 0; k < this.grey.length; ++k) {
      const g = 40 + Math.round((215 * this.grey[k]) / 255);
      d[4 * k] = g;
      d[4 * k + 1] = g;
      d[4 * k + 2] = g;
      d[4 * k + 3] = 255;
    }
    this.ctx.putImageData(this.image, 0, 0);
  }
}

// The field's directions at a 21 × 21 lattice of points, as arrows of one length.
export function drawArrows(ctx: CanvasRenderingContext2D, v: View, f: GridField, color: string) {
  const n = 21;
  const len = (v.width / n) * 0.8;
  ctx.strokeStyle = color;
  ctx.lineWidth = 1.2;
  ctx.beginPath();
  for (let a = 0; a < n; ++a)
    for (let b = 0; b < n; ++b) {
      const p = [f.min[0] + ((a + 0.5) / n) * (f.max[0] - f.min[0]), f.min[1] + ((b + 0.5) / n) * (f.max[1] - f.min[1])];
      const [u, w] = sample(f, p[0], p[1]);
      const m = Math.hypot(u, w);
      if (!(m > 0)) continue;
      const [x, y] = v.toCanvas(p);
      const dx = (len * u) / m;
      const dy = (-len * w) / m;
      const [tx, ty] = [x + dx / 2, y + dy / 2];
      ctx.moveTo(x - dx / 2, y - dy / 2);
      ctx.lineTo(tx, ty);
      ctx.moveTo(tx - 0.35 * dx + 0.2 * dy, ty - 0.35 * dy - 0.2 * dx);
      ctx.lineTo(tx, ty);
      ctx.lineTo(tx - 0.35 * dx - 0.2 * dy, ty - 0.35 * dy + 0.2 * dx);
    }
  ctx.stroke();
}
