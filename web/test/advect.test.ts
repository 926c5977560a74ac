import { describe, expect, it } from "vitest";
import { advect, Advection, gridFlow, ringMotion, shortLic, type PixelFlow } from "../src/preview/advect";

function uniform(w: number, h: number, dx: number, dy: number): PixelFlow {
  return { width: w, height: h, dx: new Float32Array(w * h).fill(dx), dy: new Float32Array(w * h).fill(dy), mask: new Uint8Array(w * h).fill(1) };
}

// A planar field on an n² grid over [−1, 1]², 3 numbers per vertex.
function grid(n: number, f: (x: number, y: number) => [number, number]) {
  const vectors: number[] = [];
  for (let iy = 0; iy < n; ++iy)
    for (let ix = 0; ix < n; ++ix) vectors.push(...f(-1 + (2 * ix) / (n - 1), -1 + (2 * iy) / (n - 1)), 0);
  return { nx: n, ny: n, min: [-1, -1] as [number, number], max: [1, 1] as [number, number], vectors };
}

// The motion around the picture's centre between steps 30 and 32 of an advection.
function motion(field: (x: number, y: number) => [number, number]) {
  const n = 96;
  const flow = gridFlow(grid(33, field), n, n, 1.5);
  const a = new Advection(n, n, { seed: 3 });
  for (let k = 0; k < 30; ++k) a.step(flow);
  const before = Float32Array.from(a.image);
  a.step(flow);
  a.step(flow);
  return ringMotion(before, a.image, n, n, n / 2, n / 2, 22);
}

describe("texture advection (the moving preview)", () => {
  it("carries the picture exactly by a whole-pixel flow", () => {
    const w = 7;
    const h = 5;
    const src = Float32Array.from({ length: w * h }, (_, k) => k * k);
    const out = new Float32Array(w * h);
    advect(src, uniform(w, h, 2, -1), out);
    // out(i, j) = src(i − 2, j + 1) inside; clamped at the edges.
    for (let j = 0; j < h; ++j)
      for (let i = 0; i < w; ++i) expect(out[j * w + i]).toBe(src[Math.min(h - 1, j + 1) * w + Math.max(0, i - 2)]);
  });

  it("interpolates bilinearly between pixels and leaves masked pixels alone", () => {
    const w = 4;
    const h = 3;
    const src = Float32Array.from({ length: w * h }, (_, k) => 3 * (k % w) + 10 * Math.floor(k / w)); // linear
    const flow = uniform(w, h, 0.25, 0.5);
    flow.mask[w + 2] = 0;
    const out = new Float32Array(w * h);
    advect(src, flow, out);
    expect(out[w + 1]).toBeCloseTo(3 * 0.75 + 10 * 0.5, 12); // pixel (1, 1), looks up (0.75, 0.5)
    expect(out[w + 2]).toBe(src[w + 2]); // masked
    expect(out[w + 3]).toBe(src[w + 3]); // its look-up touches the masked pixel
  });

  it("takes the field's direction per pixel, y down", () => {
    const f = gridFlow(grid(5, () => [3, 0]), 8, 8, 1.5);
    expect(f.dx[0]).toBeCloseTo(1.5, 6);
    expect(f.dy[0]).toBeCloseTo(0, 6);
    const g = gridFlow(grid(5, () => [0, 0.01]), 8, 8, 2);
    expect(g.dx[9]).toBeCloseTo(0, 6);
    expect(g.dy[9]).toBeCloseTo(-2, 6); // world up is picture up
    const z = gridFlow(grid(5, () => [0, 0]), 8, 8);
    expect(z.dx.every((v) => v === 0) && z.dy.every((v) => v === 0)).toBe(true);
    expect(z.mask.every((v) => v === 0)).toBe(true); // no field: nothing shown
    expect(f.mask.every((v) => v === 1)).toBe(true);
  });

  it("finds a whole-picture shift with the ring matcher", () => {
    const n = 64;
    const a = new Advection(n, n, { seed: 5 }).image;
    const b = new Float32Array(n * n);
    advect(a, uniform(n, n, 3, 0), b); // everything 3 pixels to the right
    const m = ringMotion(a, b, n, n, 32, 32, 14);
    expect(m.used).toBe(16);
    // Right is outwards on the right of the ring, inwards on the left: no mean radial
    // part, and none around.
    expect(Math.abs(m.radial)).toBeLessThan(1e-9);
    expect(Math.abs(m.tangential)).toBeLessThan(1e-9);
  });

  it("moves a source's texture outwards, a sink's inwards, a centre's round", () => {
    const source = motion((x, y) => [x, y]);
    const sink = motion((x, y) => [-x, -y]);
    const ccw = motion((x, y) => [-y, x]);
    const cw = motion((x, y) => [y, -x]);
    // Two steps of 1.5 pixels: about 3 pixels (measured 2.96 and −2.68); around the
    // centre a little less (the matcher shifts straight, the flow bends: 1.85, −2.18).
    expect(source.radial).toBeGreaterThan(2);
    expect(sink.radial).toBeLessThan(-2);
    expect(Math.abs(source.tangential)).toBeLessThan(1);
    expect(Math.abs(sink.tangential)).toBeLessThan(1);
    expect(ccw.tangential).toBeGreaterThan(1.2);
    expect(cw.tangential).toBeLessThan(-1.2);
    expect(Math.abs(ccw.radial)).toBeLessThan(1);
    expect(Math.abs(cw.radial)).toBeLessThan(1);
  });
});

describe("the short LIC of the shown picture", () => {
  it("averages along the flow and not across it", () => {
    const w = 9;
    const h = 5;
    // Columns alternate 0, 1; the flow runs down the columns: the LIC keeps them, and
    // smooths a flow across them to the mean of the walked pixels.
    const src = Float32Array.from({ length: w * h }, (_, k) => (k % w) % 2);
    const out = new Float32Array(w * h);
    shortLic(src, uniform(w, h, 0, 1.5), 2, out);
    for (let k = 0; k < w * h; ++k) expect(out[k]).toBeCloseTo(src[k], 6);
    shortLic(src, uniform(w, h, 1.5, 0), 1, out);
    const c = 2 * w + 4; // (4, 2), value 0, neighbours 1: (0 + 1 + 1) / 3
    expect(out[c]).toBeCloseTo(2 / 3, 6);
    expect(out[2 * w]).toBeCloseTo((0 + 1) / 2, 6); // at the left edge the walk back stops
  });
});
