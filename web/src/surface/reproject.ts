// Keeping the surface preview's picture on the surface when the camera moves. The
// preview's noise lives in image space (IBFV-S); left as it is, an orbit would slide the
// surface under a still picture. So when the camera changes, a pass draws the mesh with
// the new camera and writes, per pixel, where that point of the surface was on the screen
// under the previous camera (16 bits per coordinate in RGBA bytes, 1/32 pixel steps);
// each pixel of the picture then takes the value of the nearest old pixel there, and
// pixels that were not on the surface before (new in view) get values drawn from the
// picture itself (valuesLike).

// GLSL of the pass: `previous` the old camera's projection × view matrix; `resolution`
// the target's size in pixels.
export const reprojectVertex = /* glsl */ `
uniform mat4 previous;
varying vec4 vOld;
void main() {
  vOld = previous * modelMatrix * vec4(position, 1.0);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
export const reprojectFragment = /* glsl */ `
uniform vec2 resolution;
varying vec4 vOld;
vec2 bytes(float v) {
  float e = clamp(floor(v * 32.0 + 0.5), 0.0, 65534.0);
  float hi = floor(e / 256.0);
  return vec2(hi, e - 256.0 * hi) / 255.0;
}
void main() {
  if (vOld.w <= 0.0) { gl_FragColor = vec4(1.0); return; }
  vec2 px = (vOld.xy / vOld.w * 0.5 + 0.5) * resolution;
  if (px.x < 0.0 || px.y < 0.0 || px.x > resolution.x || px.y > resolution.y) { gl_FragColor = vec4(1.0); return; }
  gl_FragColor = vec4(bytes(px.x), bytes(px.y));
}`;

// The pass's read-back bytes (bottom row first, as WebGL reads them) as the old position
// of each pixel's surface point, top row first, in pixel-index coordinates (pixel (i, j)
// centred at (i, j), y down): [x0, y0, x1, y1, …], NaN where the pixel had no old place.
export function decodeOld(bytes: Uint8Array, width: number, height: number): Float32Array {
  const out = new Float32Array(2 * width * height);
  for (let j = 0; j < height; ++j)
    for (let i = 0; i < width; ++i) {
      const src = 4 * ((height - 1 - j) * width + i);
      const k = j * width + i;
      const ex = 256 * bytes[src] + bytes[src + 1];
      const ey = 256 * bytes[src + 2] + bytes[src + 3];
      if (ex === 65535 || ey === 65535) {
        out[2 * k] = NaN;
        out[2 * k + 1] = NaN;
        continue;
      }
      out[2 * k] = ex / 32 - 0.5;
      out[2 * k + 1] = height - ey / 32 - 0.5;
    }
  return out;
}

// out(k) = src at from(k) (the nearest pixel: a bilinear look-up would blur the noise
// and so lower the picture's contrast at every move of the camera) where from(k) is a
// place inside the picture that was on the surface (oldMask), else a value of `fresh()`.
export function reproject(
  src: Float32Array,
  oldMask: Uint8Array,
  width: number,
  height: number,
  from: Float32Array,
  fresh: () => number,
  out: Float32Array,
): void {
  for (let k = 0; k < width * height; ++k) {
    const i = Math.round(from[2 * k]);
    const j = Math.round(from[2 * k + 1]);
    const q = j * width + i;
    out[k] = i >= 0 && j >= 0 && i < width && j < height && oldMask[q] ? src[q] : fresh();
  }
}

// A source of values for the pixels new in view with the picture's own distribution:
// values of `src` at random pixels of `mask` (an advected picture's values are a blend of
// many noise values, with a smaller spread than fresh white noise: new white noise would
// stand out as high-contrast streaks once the short LIC draws it out along the flow).
// `random` gives numbers in [0, 1).
export function valuesLike(src: Float32Array, mask: Uint8Array, random: () => number): () => number {
  const on: number[] = [];
  for (let k = 0; k < mask.length; ++k) if (mask[k]) on.push(k);
  if (!on.length) return random;
  return () => src[on[Math.min(on.length - 1, Math.floor(random() * on.length))]];
}
