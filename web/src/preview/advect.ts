// The designer's moving, directional preview: image-based flow visualization (van Wijk
// 2002, "IBFV"; on surfaces in image space, van Wijk 2003, "IBFV-S"). Each step the
// picture is carried one step along the flow (a backward, bilinear look-up: out(x) =
// in(x − d(x))) and blended with a little fresh noise, so that spots are born, carried
// downstream and fade, leaving streaks along the flow: a source's texture moves outwards,
// a sink's inwards, a centre's round. (IBFV's periodic noise keeps each pixel's value
// steadier, but then most of the picture stands still and the motion is faint; fresh
// noise per step, as in Lagrangian–Eulerian advection, lets the carried part dominate.) The flow is given per pixel
// as a displacement in pixels (y down), with a mask of the pixels that show the domain.
// The same code runs for the planar grid (flow sampled from the grid's field) and for
// surfaces (flow: the surface's field projected to the screen, surface/preview.ts).

export interface PixelFlow {
  width: number;
  height: number;
  // Displacement per step in pixels, row-major, top row first (y grows downwards).
  dx: Float32Array;
  dy: Float32Array;
  // 1 where the pixel shows the domain, 0 elsewhere (the picture is left grey there).
  mask: Uint8Array;
}

// Repeatable white noise in [0, 1) (xorshift32).
function noise(n: number, seed: number): Float32Array {
  const out = new Float32Array(n);
  let s = seed >>> 0 || 1;
  for (let i = 0; i < n; ++i) {
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    s >>>= 0;
    out[i] = s / 4294967296;
  }
  return out;
}

// out(x) = src(x − d(x)), bilinear, clamped at the picture's edge; pixels outside the
// mask, or whose look-up lands outside it, keep their own value (nothing flows in from
// outside the domain). Exported for the tests.
export function advect(src: Float32Array, flow: PixelFlow, out: Float32Array): void {
  const { width: w, height: h, dx, dy, mask } = flow;
  for (let j = 0; j < h; ++j)
    for (let i = 0; i < w; ++i) {
      const k = j * w + i;
      if (!mask[k]) {
        out[k] = src[k];
        continue;
      }
      const x = Math.min(w - 1, Math.max(0, i - dx[k]));
      const y = Math.min(h - 1, Math.max(0, j - dy[k]));
      const i0 = Math.min(w - 2, Math.floor(x));
      const j0 = Math.min(h - 2, Math.floor(y));
      const a = x - i0;
      const b = y - j0;
      const k0 = j0 * w + i0;
      if (!mask[k0] || !mask[k0 + 1] || !mask[k0 + w] || !mask[k0 + w + 1]) {
        out[k] = src[k];
        continue;
      }
      out[k] = (1 - b) * ((1 - a) * src[k0] + a * src[k0 + 1]) + b * ((1 - a) * src[k0 + w] + a * src[k0 + w + 1]);
    }
}

export interface AdvectionOptions {
  blend?: number; // share of fresh noise per step (IBFV's α), default 0.1
  seed?: number;
}

export class Advection {
  readonly width: number;
  readonly height: number;
  image: Float32Array; // values in [0, 1], row-major, top row first
  steps = 0;
  private scratch: Float32Array;
  private lic = new Float32Array();
  private readonly blend: number;
  private seed: number;

  constructor(width: number, height: number, o: AdvectionOptions = {}) {
    this.width = width;
    this.height = height;
    this.blend = o.blend ?? 0.1;
    this.seed = (o.seed ?? 11) >>> 0 || 1;
    this.image = noise(width * height, this.seed);
    this.scratch = new Float32Array(width * height);
  }

  // The next number of the noise sequence (xorshift32), in [0, 1).
  private noise(): number {
    let s = this.seed;
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    this.seed = s >>> 0;
    return this.seed / 4294967296;
  }

  // One step along the flow (the flow's size must be the picture's).
  step(flow: PixelFlow): void {
    if (flow.width !== this.width || flow.height !== this.height) throw new Error("the flow's size is not the picture's");
    advect(this.image, flow, this.scratch);
    ++this.steps;
    const a = this.blend;
    const out = this.scratch;
    for (let k = 0; k < out.length; ++k) out[k] = (1 - a) * out[k] + a * this.noise();
    [this.image, this.scratch] = [this.scratch, this.image];
  }

  // The picture as shown: a short LIC (`lic` steps each way; 0: none) along the flow of
  // the last step, contrast stretched (grey()).
  shown(flow: PixelFlow, lic: number, out: Uint8Array): Uint8Array {
    if (lic <= 0) return this.grey(flow.mask, out);
    const image = this.image;
    if (this.lic.length !== image.length) this.lic = new Float32Array(image.length);
    shortLic(image, flow, lic, this.lic);
    this.image = this.lic;
    try {
      return this.grey(flow.mask, out);
    } finally {
      this.image = image;
    }
  }

  // Greys (0–255) of the picture with its contrast stretched (mean ± 2.5 standard
  // deviations over the masked pixels), grey 128 outside the mask.
  grey(mask?: Uint8Array, out: Uint8Array = new Uint8Array(this.image.length)): Uint8Array {
    let n = 0;
    let mean = 0;
    let sq = 0;
    for (let k = 0; k < this.image.length; ++k) {
      if (mask && !mask[k]) continue;
      ++n;
      mean += this.image[k];
      sq += this.image[k] * this.image[k];
    }
    mean /= Math.max(1, n);
    const sd = Math.sqrt(Math.max(0, sq / Math.max(1, n) - mean * mean)) || 1;
    for (let k = 0; k < this.image.length; ++k)
      out[k] = mask && !mask[k] ? 128 : Math.round(255 * Math.min(1, Math.max(0, 0.5 + (this.image[k] - mean) / (5 * sd))));
    return out;
  }
}

// A short line integral convolution of `src` along the flow (Cabral & Leedom 1993): each
// pixel the mean of `length` unit steps each way along the flow's direction (nearest-pixel
// directions, bilinear values), as `tvf render texture` shows its advected texture: the
// advected noise moves, the short LIC draws it out into streaks along the flow, so that a
// still picture shows the flow's lines too. Pixels outside the mask, or where the flow
// vanishes, keep their value; a walk stops at the mask's edge.
export function shortLic(src: Float32Array, flow: PixelFlow, length: number, out: Float32Array): void {
  const { width: w, height: h, dx, dy, mask } = flow;
  for (let j = 0; j < h; ++j)
    for (let i = 0; i < w; ++i) {
      const k = j * w + i;
      let sum = src[k];
      let count = 1;
      if (mask[k] && (dx[k] !== 0 || dy[k] !== 0))
        for (let dir = 1; dir >= -1; dir -= 2) {
          let x = i;
          let y = j;
          let q = k;
          for (let step = 0; step < length; ++step) {
            const n = Math.hypot(dx[q], dy[q]);
            if (n === 0) break;
            x += (dir * dx[q]) / n;
            y += (dir * dy[q]) / n;
            if (x < 0 || y < 0 || x > w - 1 || y > h - 1) break;
            const i0 = Math.min(w - 2, Math.floor(x));
            const j0 = Math.min(h - 2, Math.floor(y));
            q = Math.round(y) * w + Math.round(x);
            if (!mask[q]) break;
            const a = x - i0;
            const b = y - j0;
            const k0 = j0 * w + i0;
            sum += (1 - b) * ((1 - a) * src[k0] + a * src[k0 + 1]) + b * ((1 - a) * src[k0 + w] + a * src[k0 + w + 1]);
            ++count;
          }
        }
      out[k] = sum / count;
    }
}

// The flow of a planar grid field on a width × height picture of the grid (pixel (i, j)
// centred at world (xmin + (i + ½)·dx, ymax − (j + ½)·dy)): the field's direction at each
// pixel, `pixels` long (a designed field's speed falls off far from its elements, so only
// the direction is shown, as in the LIC picture). Where the field vanishes (exactly 0: far
// from every element under a steep falloff) the pixel is masked out: shown grey, not as
// a still noise.
export function gridFlow(
  f: { nx: number; ny: number; min: [number, number]; max: [number, number]; vectors: ArrayLike<number> },
  width: number,
  height: number,
  pixels = 1.5,
): PixelFlow {
  const dx = new Float32Array(width * height);
  const dy = new Float32Array(width * height);
  const mask = new Uint8Array(width * height);
  const sx = (f.max[0] - f.min[0]) / width;
  const sy = (f.max[1] - f.min[1]) / height;
  const v = f.vectors;
  for (let j = 0; j < height; ++j)
    for (let i = 0; i < width; ++i) {
      // Bilinear sample at the pixel's centre.
      const gx = ((i + 0.5) / width) * (f.nx - 1);
      const gy = (1 - (j + 0.5) / height) * (f.ny - 1);
      const ix = Math.min(f.nx - 2, Math.floor(gx));
      const iy = Math.min(f.ny - 2, Math.floor(gy));
      const a = gx - ix;
      const b = gy - iy;
      const at = (p: number, q: number, c: number) => v[3 * (q * f.nx + p) + c];
      const comp = (c: number) => (1 - b) * ((1 - a) * at(ix, iy, c) + a * at(ix + 1, iy, c)) + b * ((1 - a) * at(ix, iy + 1, c) + a * at(ix + 1, iy + 1, c));
      const pu = comp(0) / sx;
      const pv = -comp(1) / sy;
      const n = Math.hypot(pu, pv);
      if (n > 1e-12) {
        dx[j * width + i] = (pixels * pu) / n;
        dy[j * width + i] = (pixels * pv) / n;
        mask[j * width + i] = 1;
      }
    }
  return { width, height, dx, dy, mask };
}

// The mean displacement, in pixels, of the picture between `a` and `b` (greys, row-major)
// near the point (cx, cy), split into its part away from the point (radial, positive
// outwards) and its part around it (tangential, positive counter-clockwise as seen with y
// up). Patches of side 2·half + 1 on a ring of radius r are matched between the pictures
// over shifts up to `search` pixels (least squared difference). The end-to-end tests
// read the preview's motion with it; it is exported for them and for the unit tests.
export function ringMotion(
  a: ArrayLike<number>,
  b: ArrayLike<number>,
  width: number,
  height: number,
  cx: number,
  cy: number,
  r: number,
  o: { samples?: number; half?: number; search?: number } = {},
): { radial: number; tangential: number; used: number } {
  const samples = o.samples ?? 16;
  const half = o.half ?? 6;
  const search = o.search ?? 4;
  let radial = 0;
  let tangential = 0;
  let used = 0;
  for (let s = 0; s < samples; ++s) {
    const th = (2 * Math.PI * s) / samples;
    const px = Math.round(cx + r * Math.cos(th));
    const py = Math.round(cy - r * Math.sin(th));
    if (px - half - search < 0 || py - half - search < 0 || px + half + search >= width || py + half + search >= height) continue;
    let best = Infinity;
    let bu = 0;
    let bv = 0;
    for (let v = -search; v <= search; ++v)
      for (let u = -search; u <= search; ++u) {
        let e = 0;
        for (let q = -half; q <= half; ++q)
          for (let p = -half; p <= half; ++p) {
            const d = a[(py + q) * width + px + p] - b[(py + q + v) * width + px + p + u];
            e += d * d;
          }
        if (e < best) [best, bu, bv] = [e, u, v];
      }
    // The ring's outward direction (cos θ, −sin θ) in pixels (y down); counter-clockwise
    // with y up is (−sin θ, −cos θ) in pixels.
    radial += bu * Math.cos(th) - bv * Math.sin(th);
    tangential += -bu * Math.sin(th) - bv * Math.cos(th);
    ++used;
  }
  return { radial: used ? radial / used : 0, tangential: used ? tangential / used : 0, used };
}
