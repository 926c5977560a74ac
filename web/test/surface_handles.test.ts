import { describe, expect, it } from "vitest";
import type { Analysis } from "../src/api";
import type { Scene } from "../src/scene";
import { bifurcationAt, boundingRadius, surfaceHandleAt, surfaceHandles } from "../src/surface/handles";

const scene: Scene = {
  tvf: 1,
  domain: { sphere: { subdivisions: 2, radius: 1 } },
  time: { frames: 11, range: [0, 1] },
  generator: "basis",
  elements: [
    { kind: "singular", type: "source", path: [[1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, 1, 1]] },
    { kind: "singular", type: "sink", path: [[-1, 0, 0, 0]] },
  ],
};

describe("picking on a surface", () => {
  it("measures a mesh by half its bounding box's diagonal", () => {
    expect(boundingRadius([0, 0, 0, 2, 0, 0, 0, 4, 4])).toBeCloseTo(3, 12); // (2, 4, 4) / 2
    expect(boundingRadius([])).toBe(1);
    expect(boundingRadius([5, 5, 5])).toBe(1); // one point: no size
  });

  it("offers every control point of a moving element's path, with its index", () => {
    const hs = surfaceHandles(scene, 0.5);
    // The planar view's handles (the moving element at its place now, the fixed one) and
    // the three control points.
    const points = hs.filter((h) => h.handle.kind === "element" && h.handle.index === 0);
    expect(points.map((h) => h.position)).toContainEqual([0, 0, 1]);
    expect(points.map((h) => h.position)).toContainEqual([1, 0, 0]);
    expect(surfaceHandleAt(scene, 0.5, [0.02, 0, 1], 0.1)).toEqual({ kind: "element", index: 0, point: 2 });
    expect(surfaceHandleAt(scene, 0.5, [0.98, 0.02, 0], 0.1)).toEqual({ kind: "element", index: 0, point: 0 });
    expect(surfaceHandleAt(scene, 0.5, [-1, 0.03, 0], 0.1)).toEqual({ kind: "element", index: 1, point: 0 });
    expect(surfaceHandleAt(scene, 0.5, [0.7, -0.7, 0], 0.1)).toBeUndefined();
  });

  it("picks the nearest bifurcation within the radius", () => {
    const a = {
      bifurcations: [
        { t: 0.2, position: [1, 0, 0], kind: "creation", paths: [0, 1] },
        { t: 0.6, position: [0.9, 0.1, 0], kind: "cancellation", paths: [0, 1] },
      ],
    } as unknown as Analysis;
    expect(bifurcationAt(a, [0.92, 0.08, 0], 0.2)).toBe(1);
    expect(bifurcationAt(a, [1, -0.01, 0], 0.2)).toBe(0);
    expect(bifurcationAt(a, [0, 0, 1], 0.2)).toBe(-1);
    expect(bifurcationAt(undefined, [1, 0, 0], 0.2)).toBe(-1);
  });
});
