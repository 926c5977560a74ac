import { describe, expect, it } from "vitest";
import type { Analysis } from "../src/api";
import { ORBIT_ATTRACTING, ORBIT_REPELLING, orbitsAt } from "../src/orbits";

describe("orbitsAt", () => {
  const orbit = (frame: number, stability: string, points: number[][]) =>
    ({ frame, t: frame / 10, center: [0, 0, 0], radius: 1, stability, points, id: 0 });
  const analysis = {
    periodic_orbits: [
      orbit(3, "attracting", [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]]),
      orbit(3, "repelling", [[2, 0, 0], [0, 2, 0], [-2, 0, 0]]),
      orbit(4, "attracting", [[1, 0, 0], [0, 1, 0], [-1, 0, 0]]),
      orbit(3, "attracting", [[1, 0, 0], [0, 1, 0]]), // too few points to be a loop
    ],
  } as unknown as Analysis;
  it("gives the frame's loops, closed, coloured by stability", () => {
    const loops = orbitsAt(analysis, 3);
    expect(loops.length).toBe(2);
    expect(loops[0]).toEqual({ points: [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [1, 0, 0]], color: ORBIT_ATTRACTING });
    expect(loops[1].color).toBe(ORBIT_REPELLING);
    expect(orbitsAt(analysis, 5)).toEqual([]);
    expect(orbitsAt(undefined, 3)).toEqual([]);
    expect(orbitsAt({} as Analysis, 3)).toEqual([]);
  });
});
