// The singularity paths through time on a surface: the analysis's paths drawn on the mesh
// as lines coloured by time (timeColor: dark blue at the first time, through teal and
// green, to yellow at the last), a white ball where a path is born, a black one where it
// dies (inside the time range), and the bifurcations as diamonds. The time strip
// (timestrip.ts) uses the same colours.
import * as THREE from "three";
import type { Analysis } from "../api";
import { BIFURCATION_COLOR } from "../colors";

// Colour of time u ∈ [0, 1] (a viridis-like ramp), as [r, g, b] in [0, 1].
export function timeColor(u: number): [number, number, number] {
  const stops: [number, number, number][] = [
    [0.27, 0.0, 0.33],
    [0.23, 0.32, 0.55],
    [0.13, 0.57, 0.55],
    [0.37, 0.79, 0.38],
    [0.99, 0.91, 0.14],
  ];
  const x = Math.min(1, Math.max(0, u)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  const a = x - i;
  return [0, 1, 2].map((k) => (1 - a) * stops[i][k] + a * stops[i + 1][k]) as [number, number, number];
}

export function timeCss(u: number): string {
  const [r, g, b] = timeColor(u);
  return `rgb(${Math.round(255 * r)}, ${Math.round(255 * g)}, ${Math.round(255 * b)})`;
}

// The objects of the paths on a mesh of bounding radius `radius`; `selected` the index of
// the picked bifurcation (drawn larger).
export function pathObjects(a: Analysis, range: [number, number], radius: number, selected = -1): THREE.Object3D[] {
  const out: THREE.Object3D[] = [];
  const span = range[1] - range[0] || 1;
  const eps = 1e-6 * span;
  const positions: number[] = [];
  const colors: number[] = [];
  for (const path of a.paths) {
    for (let k = 0; k + 1 < path.points.length; ++k) {
      const [p, q] = [path.points[k], path.points[k + 1]];
      positions.push(p[0], p[1], p[2] ?? 0, q[0], q[1], q[2] ?? 0);
      colors.push(...timeColor((p[3] - range[0]) / span), ...timeColor((q[3] - range[0]) / span));
    }
    const ball = (at: number[], color: number) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.012 * radius, 8, 6), new THREE.MeshBasicMaterial({ color }));
      m.position.set(at[0], at[1], at[2] ?? 0);
      out.push(m);
    };
    if (path.points.length && path.birth > range[0] + eps) ball(path.points[0], 0xffffff);
    if (path.points.length && path.death < range[1] - eps) ball(path.points[path.points.length - 1], 0x000000);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.Float32BufferAttribute(positions, 3));
  g.setAttribute("color", new THREE.Float32BufferAttribute(colors, 3));
  const lines = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true, depthTest: true }));
  lines.renderOrder = 1;
  out.push(lines);
  a.bifurcations.forEach((b, i) => {
    const size = (i === selected ? 0.04 : 0.025) * radius;
    const m = new THREE.Mesh(new THREE.OctahedronGeometry(size), new THREE.MeshBasicMaterial({ color: BIFURCATION_COLOR }));
    m.position.set(b.position[0], b.position[1], b.position[2] ?? 0);
    out.push(m);
  });
  return out;
}
