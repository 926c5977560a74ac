// The planar grid's moving preview: texture advection (advect.ts) on a square picture of
// the grid, stepped by the page's ticker (ticker.ts) and drawn under the design.
import type { GridField } from "../lic";
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
