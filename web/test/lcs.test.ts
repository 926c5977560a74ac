import { describe, expect, it } from "vitest";
import { magma } from "../src/lcs";

// The overlay's colours are tvf ftle's (render/lcs_pictures.cpp's magma stops).
describe("magma", () => {
  it("runs from the first stop to the last, clamped outside [0, 1]", () => {
    expect(magma(0)).toEqual([0, 0, 4]);
    expect(magma(1)).toEqual([252, 253, 191]);
    expect(magma(-3)).toEqual([0, 0, 4]);
    expect(magma(7)).toEqual([252, 253, 191]);
    expect(magma(0.5)).toEqual([181, 54, 122]); // the middle stop of nine
  });
  it("interpolates linearly between stops, ever brighter", () => {
    expect(magma(1 / 16)).toEqual([14, 8, 36]); // half way from stop 0 to stop 1
    let last = -1;
    for (let i = 0; i <= 100; ++i) {
      const [r, g, b] = magma(i / 100);
      expect(r + g + b).toBeGreaterThanOrEqual(last); // monotone in brightness (the e2e test relies on it)
      last = r + g + b;
    }
  });
});
