// Drawing a pathline in the space-time view (x, y across, design time up), as pure
// geometry so that it is tested without a browser.
//
// A drag on the screen is two-dimensional; a pathline is a curve in (x, y, t). The view
// resolves the missing dimension the way it is seen:
// 1. The press picks the start on the current-time plane (the translucent slab): the
//    point of the domain under the pointer at the current time, which is where a
//    particle released on the pathline starts.
// 2. The drag then draws on the upright plane through that point that faces the camera
//    (it holds the time axis and the camera's left–right direction). Every point of the
//    stroke is where the pointer's ray meets that plane, so the curve lands exactly under
//    the pointer: up is later, sideways is moving across the domain.
// To draw a pathline in another direction, orbit the view first (the plane turns with
// the camera); to start at another time, move the timeline first (the plane moves).
// The picked points are clamped into the domain and the time range, ordered by time
// (a stroke drawn downwards is read from its lower end), and kept where time strictly
// increases (a pathline cannot go back in time).

export type V3 = [number, number, number];

export interface Ray {
  origin: V3;
  direction: V3;
}

export interface Plane {
  point: V3;
  normal: V3;
}

const dot = (a: V3, b: V3) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

// Where the ray meets the plane (in front of its origin), or undefined.
export function intersect(ray: Ray, plane: Plane): V3 | undefined {
  const denom = dot(ray.direction, plane.normal);
  if (Math.abs(denom) < 1e-9) return undefined;
  const d: V3 = [plane.point[0] - ray.origin[0], plane.point[1] - ray.origin[1], plane.point[2] - ray.origin[2]];
  const s = dot(d, plane.normal) / denom;
  if (!(s > 0)) return undefined;
  return [ray.origin[0] + s * ray.direction[0], ray.origin[1] + s * ray.direction[1], ray.origin[2] + s * ray.direction[2]];
}

// The horizontal plane of one time (view z = height).
export function timePlane(height: number): Plane {
  return { point: [0, 0, height], normal: [0, 0, 1] };
}

// The upright plane through p facing a camera that looks along `view` (z is time, up):
// its normal is the horizontal part of the viewing direction. Undefined when the camera
// looks (almost) straight down or up: the plane would be seen edge-on.
export function uprightPlane(p: V3, view: V3): Plane | undefined {
  const h = Math.hypot(view[0], view[1]);
  if (h < 0.05 * Math.hypot(view[0], view[1], view[2])) return undefined;
  return { point: p, normal: [view[0] / h, view[1] / h, 0] };
}

export interface SpaceTimeBox {
  min: [number, number]; // the domain's rectangle
  max: [number, number];
  range: [number, number]; // the time range
}

// Rounds as the scene file keeps positions (1e-4).
const r4 = (v: number) => Math.round(v * 1e4) / 1e4;

// The control points [x, y, t] of the pathline a stroke of [x, y, t] points makes:
// clamped into the box, ordered by time, strictly increasing in time, resampled to
// `count` points evenly spaced along the curve (x and y measured in domain widths, t in
// time ranges, so that neither dominates). Throws when the stroke does not rise in time
// by at least 2 % of the time range.
export function spaceTimePathline(stroke: number[][], box: SpaceTimeBox, count = 6): number[][] {
  const [t0, t1] = box.range;
  const span = t1 - t0;
  const wx = box.max[0] - box.min[0];
  const wy = box.max[1] - box.min[1];
  const clamp = (v: number, a: number, b: number) => Math.min(b, Math.max(a, v));
  let pts = stroke.map((p) => [clamp(p[0], box.min[0], box.max[0]), clamp(p[1], box.min[1], box.max[1]), clamp(p[2], t0, t1)]);
  if (pts.length < 2) throw new Error("drag upwards from the time plane to draw a pathline (time is the vertical axis)");
  if (pts[pts.length - 1][2] < pts[0][2]) pts = pts.reverse();
  const rising: number[][] = [pts[0]];
  for (const p of pts.slice(1)) if (p[2] > rising[rising.length - 1][2] + 1e-4 * span) rising.push(p);
  if (rising.length < 2 || rising[rising.length - 1][2] - rising[0][2] < 0.02 * span)
    throw new Error("a pathline must rise in time: drag upwards from the time plane (time is the vertical axis)");
  // Arc length in normalised space-time.
  const u = rising.map((p) => [(p[0] - box.min[0]) / wx, (p[1] - box.min[1]) / wy, (p[2] - t0) / span]);
  const s = [0];
  for (let i = 1; i < u.length; ++i) s.push(s[i - 1] + Math.hypot(u[i][0] - u[i - 1][0], u[i][1] - u[i - 1][1], u[i][2] - u[i - 1][2]));
  const total = s[s.length - 1];
  const out: number[][] = [];
  let seg = 0;
  for (let k = 0; k < count; ++k) {
    const target = (total * k) / (count - 1);
    while (seg + 2 < rising.length && s[seg + 1] < target) ++seg;
    const len = s[seg + 1] - s[seg];
    const w = len > 0 ? clamp((target - s[seg]) / len, 0, 1) : 0;
    const a = rising[seg];
    const b = rising[seg + 1];
    const q = [r4(a[0] + w * (b[0] - a[0])), r4(a[1] + w * (b[1] - a[1])), r4(a[2] + w * (b[2] - a[2]))];
    if (out.length === 0 || q[2] > out[out.length - 1][2]) out.push(q);
  }
  return out;
}
