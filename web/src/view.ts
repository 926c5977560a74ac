// The planar canvas's mapping between world coordinates (y up) and canvas pixels (y down),
// with the domain's bounding box fitted into the canvas.
export class View {
  readonly scale: number;
  readonly ox: number;
  readonly oy: number;
  constructor(
    readonly width: number,
    readonly height: number,
    readonly min: [number, number],
    readonly max: [number, number],
  ) {
    this.scale = Math.min(width / (max[0] - min[0]), height / (max[1] - min[1]));
    this.ox = (width - this.scale * (max[0] - min[0])) / 2;
    this.oy = (height - this.scale * (max[1] - min[1])) / 2;
  }
  toCanvas(p: ArrayLike<number>): [number, number] {
    return [this.ox + (p[0] - this.min[0]) * this.scale, this.oy + (this.max[1] - p[1]) * this.scale];
  }
  toWorld(x: number, y: number): [number, number] {
    return [this.min[0] + (x - this.ox) / this.scale, this.max[1] - (y - this.oy) / this.scale];
  }
  // World length of `pixels` canvas pixels.
  worldLength(pixels: number): number {
    return pixels / this.scale;
  }
}

// Rounds world coordinates for the scene file (1e-4 of a unit is plenty for a design).
export function rounded(p: ArrayLike<number>): number[] {
  return Array.from(p, (v) => Math.round(v * 1e4) / 1e4);
}
