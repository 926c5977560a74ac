import { describe, expect, it } from "vitest";
import { lic, noise, sample, type GridField } from "../src/lic";
import { resample } from "../src/stroke";
import { View } from "../src/view";

function grid(n: number, f: (x: number, y: number) => [number, number]): GridField {
  const vectors: number[] = [];
  for (let iy = 0; iy < n; ++iy)
    for (let ix = 0; ix < n; ++ix) {
      const [u, v] = f(-1 + (2 * ix) / (n - 1), -1 + (2 * iy) / (n - 1));
      vectors.push(u, v, 0);
    }
  return { nx: n, ny: n, min: [-1, -1], max: [1, 1], vectors };
}

// Mean squared difference between neighbouring pixels along x and along y.
function roughness(img: Float32Array, w: number, h: number): [number, number] {
  let ax = 0;
  let ay = 0;
  for (let j = 0; j + 1 < h; ++j)
    for (let i = 0; i + 1 < w; ++i) {
      ax += (img[j * w + i + 1] - img[j * w + i]) ** 2;
      ay += (img[(j + 1) * w + i] - img[j * w + i]) ** 2;
    }
  return [ax, ay];
}

describe("LIC preview", () => {
  it("samples a linear field exactly (bilinear interpolation)", () => {
    const f = grid(9, (x, y) => [2 * x - y, 0.5 * y]);
    const [u, v] = sample(f, 0.33, -0.71);
    expect(u).toBeCloseTo(2 * 0.33 + 0.71, 12);
    expect(v).toBeCloseTo(-0.355, 12);
    expect(sample(f, 1.5, 0)).toEqual([0, 0]);
  });

  it("smears noise along the field: streaks along x for a flow along x, along y for one along y", () => {
    const w = 64;
    const n = noise(w, w, 3);
    const [ax, ay] = roughness(lic(grid(9, () => [1, 0]), { width: w, height: w, noise: n, length: 8 }), w, w);
    expect(ax * 5).toBeLessThan(ay);
    const [bx, by] = roughness(lic(grid(9, () => [0, 1]), { width: w, height: w, noise: n, length: 8 }), w, w);
    expect(by * 5).toBeLessThan(bx);
  });

  it("keeps values in [0, 1]", () => {
    const img = lic(grid(9, (x, y) => [-y, x]), { width: 32, height: 32 });
    expect(Math.min(...img)).toBeGreaterThanOrEqual(0);
    expect(Math.max(...img)).toBeLessThanOrEqual(1);
  });
});

describe("strokes and the view", () => {
  it("resamples a stroke evenly by arc length", () => {
    const r = resample([[0, 0], [0.1, 0], [3, 0]], 4);
    expect(r).toEqual([[0, 0], [1, 0], [2, 0], [3, 0]]);
  });

  it("maps world to canvas and back, y up in the world", () => {
    const v = new View(400, 200, [-1, -1], [1, 1]);
    expect(v.toCanvas([-1, 1])).toEqual([100, 0]);
    expect(v.toCanvas([1, -1])).toEqual([300, 200]);
    const [x, y] = v.toWorld(...v.toCanvas([0.3, -0.2]));
    expect(x).toBeCloseTo(0.3, 12);
    expect(y).toBeCloseTo(-0.2, 12);
  });
});
