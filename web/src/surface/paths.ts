// The singularity paths through time on a surface: the analysis's paths drawn on the mesh
// as thin tubes coloured by time (timeColor: dark blue at the first time, through teal and
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
  const material = new THREE.MeshBasicMaterial({ vertexColors: true });
  for (const path of a.paths) {
    // A tube along the path's points, each ring coloured by the time there.
    const pts = path.points.map((p) => new THREE.Vector3(p[0], p[1], p[2] ?? 0));
    if (pts.length >= 2) {
      const segments = Math.min(2000, 2 * (pts.length - 1));
      const radial = 6;
      const tube = new THREE.TubeGeometry(new THREE.CatmullRomCurve3(pts, false, "centripetal"), segments, 0.007 * radius, radial, false);
      const colors = new Float32Array(3 * tube.getAttribute("position").count);
      for (let i = 0; i <= segments; ++i) {
        const x = (i / segments) * (pts.length - 1);
        const k = Math.min(pts.length - 2, Math.floor(x));
        const t = (1 - (x - k)) * path.points[k][3] + (x - k) * path.points[k + 1][3];
        const c = timeColor((t - range[0]) / span);
        for (let r = 0; r <= radial; ++r) colors.set(c, 3 * (i * (radial + 1) + r));
      }
      tube.setAttribute("color", new THREE.BufferAttribute(colors, 3));
      out.push(new THREE.Mesh(tube, material));
    }
    const ball = (at: number[], color: number) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.012 * radius, 8, 6), new THREE.MeshBasicMaterial({ color }));
      m.position.set(at[0], at[1], at[2] ?? 0);
      out.push(m);
    };
    if (path.points.length && path.birth > range[0] + eps) ball(path.points[0], 0xffffff);
    if (path.points.length && path.death < range[1] - eps) ball(path.points[path.points.length - 1], 0x000000);
  }
  a.bifurcations.forEach((b, i) => {
    const size = (i === selected ? 0.04 : 0.025) * radius;
    const m = new THREE.Mesh(new THREE.OctahedronGeometry(size), new THREE.MeshBasicMaterial({ color: BIFURCATION_COLOR }));
    m.position.set(b.position[0], b.position[1], b.position[2] ?? 0);
    out.push(m);
  });
  return out;
}
