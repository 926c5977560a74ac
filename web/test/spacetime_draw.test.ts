import { describe, expect, it } from "vitest";
import * as S from "../src/scene";
import { intersect, spaceTimePathline, timePlane, uprightPlane, type V3 } from "../src/spacetime_draw";

const box = { min: [-1, -1] as [number, number], max: [1, 1] as [number, number], range: [0, 1] as [number, number] };

describe("drawing in the space-time view", () => {
  it("picks the start on the time plane and draws on the upright plane facing the camera", () => {
    // A camera above and in front, looking at the origin.
    const eye: V3 = [3, -4, 3];
    const dir = (to: V3): V3 => {
      const d: V3 = [to[0] - eye[0], to[1] - eye[1], to[2] - eye[2]];
      const n = Math.hypot(...d);
      return [d[0] / n, d[1] / n, d[2] / n];
    };
    const start = intersect({ origin: eye, direction: dir([0.2, 0.1, 0.5]) }, timePlane(0.5))!;
    start.forEach((v, k) => expect(v).toBeCloseTo([0.2, 0.1, 0.5][k], 12));
    const plane = uprightPlane(start, dir([0, 0, 0]))!;
    expect(plane.normal[2]).toBe(0);
    // A ray through a point of that plane meets it there: what is drawn lands under the pointer.
    const n = plane.normal;
    const q: V3 = [start[0] + 0.3 * -n[1], start[1] + 0.3 * n[0], 1.4]; // sideways and up
    const back = intersect({ origin: eye, direction: dir(q) }, plane)!;
    back.forEach((v, k) => expect(v).toBeCloseTo(q[k], 12));
    // Looking straight down, the upright plane would be edge-on.
    expect(uprightPlane(start, [0, 0, -1])).toBeUndefined();
    // A ray parallel to a plane, or pointing away from it, meets nothing.
    expect(intersect({ origin: [0, 0, 1], direction: [1, 0, 0] }, timePlane(0))).toBeUndefined();
    expect(intersect({ origin: [0, 0, 1], direction: [0, 0, 1] }, timePlane(0))).toBeUndefined();
  });

  it("makes control points that rise strictly in time, clamped into the domain and the time range", () => {
    const stroke = [
      [0, 0, 0.2],
      [0.1, 0, 0.3],
      [0.2, 0, 0.29], // back in time: dropped
      [0.4, 0, 0.6],
      [1.5, 0, 1.3], // outside: clamped to x = 1, t = 1
    ];
    const line = spaceTimePathline(stroke, box, 6);
    expect(line).toHaveLength(6);
    expect(line[0]).toEqual([0, 0, 0.2]);
    expect(line[5]).toEqual([1, 0, 1]);
    for (let i = 1; i < line.length; ++i) expect(line[i][2]).toBeGreaterThan(line[i - 1][2]);
    for (const p of line) expect(p[1]).toBe(0);
  });

  it("reads a stroke drawn downwards from its lower end and refuses one that does not rise", () => {
    const down = spaceTimePathline([[0.5, 0.5, 0.9], [0, 0, 0.5], [-0.5, -0.5, 0.1]], box, 3);
    expect(down.map((p) => p[2])).toEqual([0.1, 0.5, 0.9]);
    expect(down[0].slice(0, 2)).toEqual([-0.5, -0.5]);
    expect(() => spaceTimePathline([[0, 0, 0.5], [0.8, 0, 0.505]], box)).toThrow(/rise in time/);
    expect(() => spaceTimePathline([[0, 0, 0.5]], box)).toThrow(/drag upwards/);
  });

  it("spaces the points evenly along the curve in normalised space-time", () => {
    // Up for half the time range (0.5), then across the domain's width (1 in domain widths,
    // 2 in x): the middle point lies a quarter of a width past the corner.
    const line = spaceTimePathline([[-1, 0, 0], [-1, 0, 0.5], [1, 0, 0.502]], box, 3);
    expect(line[1][0]).toBeCloseTo(-0.5, 3);
    expect(line[1][2]).toBeCloseTo(0.5, 3);
  });

  it("becomes a regular element whose pathline keeps the drawn times", () => {
    const line = [[0, 0, 0.1], [0.2, 0.1, 0.5], [0.4, 0, 0.8]];
    const s = S.addTimedPathline(S.emptyScene(), line);
    expect(s.elements).toEqual([{ kind: "regular", pathline: line }]);
    expect(() => S.addTimedPathline(S.emptyScene(), [[0, 0, 0.5], [1, 0, 0.4]])).toThrow(/does not come after/);
    expect(() => S.addTimedPathline(S.emptyScene(), [[0, 0, 0.5], [1, 0, 1.5]])).toThrow(/outside the time range/);
    expect(() => S.addTimedPathline(S.emptyScene(), [[0, 0, 0.5]])).toThrow(/two points/);
  });
});
