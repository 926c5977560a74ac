// The analysis's periodic orbits (closed streamlines around foci; docs/analysis.md,
// "Periodic orbits") at one frame, as loops to draw: on the planar view over the field, on a
// surface as tubes on the mesh, in the space-time view at their times. Attracting cycles
// orange, repelling teal, as in `tvf analyze`'s space-time picture.
import type { Analysis } from "./api";

export const ORBIT_ATTRACTING = "#ee800d";
export const ORBIT_REPELLING = "#009999";

export type Orbit = NonNullable<Analysis["periodic_orbits"]>[number];

export function orbitColor(o: Orbit): string {
  return o.stability === "attracting" ? ORBIT_ATTRACTING : ORBIT_REPELLING;
}

// The loops of frame j (none without an analysis or orbits): each closed (its first point
// repeated at the end).
export function orbitsAt(analysis: Analysis | undefined, frame: number): { points: number[][]; color: string }[] {
  return (analysis?.periodic_orbits ?? [])
    .filter((o) => o.frame === frame && o.points.length >= 3)
    .map((o) => ({ points: [...o.points, o.points[0]], color: orbitColor(o) }));
}
