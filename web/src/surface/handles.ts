// What a press on a surface picks: the design's handles (those of the planar view,
// scene.ts's handles(), and every control point of the singular elements' paths, moved in
// space with their times kept) and the analysis's bifurcations; "near" is a share of the
// mesh's size (boundingRadius). Pure functions of the scene, the analysis and the mesh.
import type { Analysis } from "../api";
import * as S from "../scene";

// Half the diagonal of the bounding box of [x, y, z, …] vertices (1 for none).
export function boundingRadius(vertices: ArrayLike<number>): number {
  if (!vertices.length) return 1;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let k = 0; k < vertices.length; ++k) {
    lo[k % 3] = Math.min(lo[k % 3], vertices[k]);
    hi[k % 3] = Math.max(hi[k % 3], vertices[k]);
  }
  return Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2 || 1;
}

export function surfaceHandles(scene: S.Scene, t: number): { handle: S.Handle; position: S.Vec }[] {
  const out = S.handles(scene, t);
  (scene.elements ?? []).forEach((e, index) => {
    if (e.kind === "singular" && e.path.length > 1) e.path.forEach((q, point) => out.push({ handle: { kind: "element", index, point }, position: q.slice(0, -1) }));
  });
  return out;
}

// The handle nearest to p within `radius`, if any.
export function surfaceHandleAt(scene: S.Scene, t: number, p: S.Vec, radius: number): S.Handle | undefined {
  let best: S.Handle | undefined;
  let bestD = radius;
  for (const h of surfaceHandles(scene, t)) {
    const d = Math.hypot(...h.position.map((x, k) => x - p[k]));
    if (d <= bestD) [best, bestD] = [h.handle, d];
  }
  return best;
}

// The index of the analysis's bifurcation nearest to p within `radius`, or −1.
export function bifurcationAt(a: Analysis | undefined, p: S.Vec, radius: number): number {
  let best = -1;
  let bestD = radius;
  a?.bifurcations.forEach((b, i) => {
    const d = Math.hypot(...p.map((x, k) => x - (b.position[k] ?? 0)));
    if (d < bestD) [best, bestD] = [i, d];
  });
  return best;
}
