// Line integral convolution (Cabral & Leedom 1993) of one frame of a planar grid field:
// white noise smeared along the field's streamlines, a still picture. The page's preview
// is now the moving texture of preview/advect.ts (a still picture shows a source and a
// sink alike); the grid field's type and its bilinear sample() here serve both.

export interface GridField {
  nx: number;
  ny: number;
  min: [number, number];
  max: [number, number];
  // World vectors per grid vertex, index iy·nx + ix (DESIGN §11), 3 numbers each.
  vectors: ArrayLike<number>;
}

// Bilinear sample of the field at world point (x, y); [0, 0] outside the grid.
export function sample(f: GridField, x: number, y: number): [number, number] {
  const gx = ((x - f.min[0]) / (f.max[0] - f.min[0])) * (f.nx - 1);
  const gy = ((y - f.min[1]) / (f.max[1] - f.min[1])) * (f.ny - 1);
  if (!(gx >= 0 && gy >= 0 && gx <= f.nx - 1 && gy <= f.ny - 1)) return [0, 0];
  const ix = Math.min(f.nx - 2, Math.floor(gx));
  const iy = Math.min(f.ny - 2, Math.floor(gy));
  const wx = gx - ix;
  const wy = gy - iy;
  const v = f.vectors;
  const at = (i: number, j: number, c: number) => v[3 * (j * f.nx + i) + c];
  const out: [number, number] = [0, 0];
  for (let c = 0; c < 2; ++c)
    out[c] =
      (1 - wy) * ((1 - wx) * at(ix, iy, c) + wx * at(ix + 1, iy, c)) +
      wy * ((1 - wx) * at(ix, iy + 1, c) + wx * at(ix + 1, iy + 1, c));
  return out;
}

// A repeatable white noise image (xorshift32).
export function noise(width: number, height: number, seed = 1): Float32Array {
  const n = new Float32Array(width * height);
  let s = seed >>> 0 || 1;
  for (let i = 0; i < n.length; ++i) {
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    s >>>= 0;
    n[i] = s / 4294967296;
  }
  return n;
}

export interface LicOptions {
  width: number;
  height: number;
  length?: number; // pixels integrated each way (default width / 20)
  noise?: Float32Array; // width × height, row-major, top row first
}

// LIC image (width × height, row-major, top row first, values in [0, 1]) of the field.
// Pixel (i, j) has its centre at world (xmin + (i + ½)·dx, ymax − (j + ½)·dy). The field's
// direction is sampled once per pixel; each step then moves one pixel along the direction
// of the pixel it is in (the field's speed does not matter), `length` steps each way.
export function lic(f: GridField, o: LicOptions): Float32Array {
  const { width: w, height: h } = o;
  const length = Math.max(1, Math.round(o.length ?? w / 20));
  const tex = o.noise ?? noise(w, h);
  const dx = (f.max[0] - f.min[0]) / w;
  const dy = (f.max[1] - f.min[1]) / h;
  // Unit direction per pixel, in pixels (y down); 0 where the field vanishes.
  const du = new Float32Array(w * h);
  const dv = new Float32Array(w * h);
  for (let j = 0; j < h; ++j)
    for (let i = 0; i < w; ++i) {
      const [u, v] = sample(f, f.min[0] + (i + 0.5) * dx, f.max[1] - (j + 0.5) * dy);
      const pu = u / dx;
      const pv = -v / dy;
      const n = Math.hypot(pu, pv);
      if (n > 1e-12) {
        du[j * w + i] = pu / n;
        dv[j * w + i] = pv / n;
      }
    }
  const out = new Float32Array(w * h);
  for (let j = 0; j < h; ++j) {
    for (let i = 0; i < w; ++i) {
      let sum = tex[j * w + i];
      let count = 1;
      for (let dir = 1; dir >= -1; dir -= 2) {
        let x = i + 0.5;
        let y = j + 0.5;
        let k = j * w + i;
        for (let step = 0; step < length; ++step) {
          const a = du[k];
          const b = dv[k];
          if (a === 0 && b === 0) break;
          x += dir * a;
          y += dir * b;
          if (x < 0 || y < 0 || x >= w || y >= h) break;
          k = Math.floor(y) * w + Math.floor(x);
          sum += tex[k];
          ++count;
        }
      }
      out[j * w + i] = sum / count;
    }
  }
  // Contrast stretch: mean ± 2.5 standard deviations to [0, 1].
  let mean = 0;
  for (let k = 0; k < out.length; ++k) mean += out[k];
  mean /= out.length;
  let variance = 0;
  for (let k = 0; k < out.length; ++k) variance += (out[k] - mean) * (out[k] - mean);
  const sd = Math.sqrt(variance / out.length) || 1;
  for (let k = 0; k < out.length; ++k) out[k] = Math.min(1, Math.max(0, 0.5 + (out[k] - mean) / (5 * sd)));
  return out;
}
