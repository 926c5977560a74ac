import { describe, expect, it } from "vitest";
import { decodeOld, reproject, valuesLike } from "../src/surface/reproject";

// Bytes of the reprojection pass for pixel-index positions (x, y) (y down) on a w × h
// target, as the shader writes them (1/32-pixel steps, bottom row first); null: none.
function encode(places: ([number, number] | null)[], w: number, h: number): Uint8Array {
  const bytes = new Uint8Array(4 * w * h);
  places.forEach((p, k) => {
    const i = k % w;
    const j = Math.floor(k / w);
    const dst = 4 * ((h - 1 - j) * w + i);
    if (!p) return bytes.fill(255, dst, dst + 4);
    const ex = Math.round((p[0] + 0.5) * 32);
    const ey = Math.round((h - p[1] - 0.5) * 32);
    bytes.set([ex >> 8, ex & 255, ey >> 8, ey & 255], dst);
  });
  return bytes;
}

describe("reprojection of the surface preview", () => {
  it("decodes the pass's bytes to old pixel places, top row first, NaN for none", () => {
    const w = 3;
    const h = 2;
    const from = decodeOld(encode([[0, 0], [1.5, 0.25], null, [2, 1], [0.03125, 1], [1, 0]], w, h), w, h);
    expect(Array.from(from.slice(0, 4))).toEqual([0, 0, 1.5, 0.25]);
    expect(Number.isNaN(from[4]) && Number.isNaN(from[5])).toBe(true);
    expect(Array.from(from.slice(6))).toEqual([2, 1, 0.03125, 1, 1, 0]);
  });

  it("carries the picture with the surface: a shift by one pixel moves every value with it", () => {
    const w = 5;
    const h = 4;
    const src = Float32Array.from({ length: w * h }, (_, k) => k / 100);
    const mask = new Uint8Array(w * h).fill(1);
    // The surface moved one pixel right: new pixel (i, j) shows what old (i − 1, j) showed.
    const places = Array.from({ length: w * h }, (_, k) => [(k % w) - 1, Math.floor(k / w)] as [number, number]);
    const from = decodeOld(encode(places, w, h), w, h);
    const out = new Float32Array(w * h);
    reproject(src, mask, w, h, from, () => -1, out);
    for (let j = 0; j < h; ++j) for (let i = 0; i < w; ++i) expect(out[j * w + i]).toBe(i === 0 ? -1 : src[j * w + i - 1]);
    // A fraction of a pixel: the nearest one (no blur).
    const near = decodeOld(encode(places.map(([x, y]) => [x + 0.25, y - 0.375] as [number, number]), w, h), w, h);
    reproject(src, mask, w, h, near, () => -1, out);
    expect(out[2 * w + 2]).toBe(src[2 * w + 1]);
    // Where the old place was off the surface: a fresh value.
    mask[w + 1] = 0;
    reproject(src, mask, w, h, from, () => -1, out);
    expect(out[w + 2]).toBe(-1);
    expect(out[w + 3]).toBe(src[w + 2]);
  });

  it("draws the values of pixels new in view from the picture's own values on the surface", () => {
    const src = Float32Array.from([0.2, 0.9, 0.4, 0.7]);
    const mask = Uint8Array.from([1, 0, 1, 0]);
    let r = 0;
    const fresh = valuesLike(src, mask, () => [0, 0.49, 0.5, 0.99][r++ % 4]);
    expect([fresh(), fresh(), fresh(), fresh()].map((x) => Math.round(x * 10) / 10)).toEqual([0.2, 0.2, 0.4, 0.4]);
    expect(valuesLike(src, new Uint8Array(4), () => 0.3)()).toBe(0.3);
  });
});
