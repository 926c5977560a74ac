// The scene as the designer changes it (DESIGN §10, docs/scene_reference.md). Every
// function here is pure: it returns a new scene and leaves its argument as it was, so
// the caller can send the result to the server (which validates it) and undo is the
// server's. Positions are world coordinates: [x, y] on planar grids, [x, y, z] on
// surfaces; path points add the time t.

export type Vec = number[];

export interface SingularElement {
  kind: "singular";
  type?: string;
  jacobian?: number[][];
  path: Vec[];
  transform?: unknown[];
}
export interface RegularElement {
  kind: "regular";
  pathline: Vec[];
  attach?: number;
}
export interface BifurcationElement {
  kind: "bifurcation";
  type: string;
  at: Vec;
  scale: number;
  time_scale: number;
  angle: number;
}
// A sketched streakline (issue 20): dye released from points[0] over [from, t] has this
// shape at t (points without time; the constrained and spacetime generators reproduce it).
export interface StreaklineElement {
  kind: "streakline";
  points: Vec[];
  t: number;
  from: number;
  attach?: number;
}
export type Element = SingularElement | RegularElement | BifurcationElement | StreaklineElement;

export interface KeyframeElement {
  kind: "singular" | "regular";
  type?: string;
  jacobian?: number[][];
  at: Vec;
  vector?: Vec;
}
export interface Keyframe {
  t: number;
  elements?: KeyframeElement[];
  streamlines?: { points: Vec[]; speed?: number }[];
  field?: string;
}

export interface Scene {
  tvf: number;
  description?: string;
  domain: { grid?: { size: number[]; min: number[]; max: number[] }; mesh?: string; sphere?: unknown; torus?: unknown };
  time: { frames: number; range: number[] };
  generator: string;
  solver?: Record<string, unknown>;
  falloff?: number;
  elements?: Element[];
  keyframes?: Keyframe[];
  deform?: unknown;
  edits?: unknown[];
  [key: string]: unknown;
}

export const SINGULAR_TYPES = [
  "source",
  "sink",
  "saddle",
  "ccw_center",
  "cw_center",
  "repelling_focus",
  "attracting_focus",
] as const;

export const BIFURCATION_TYPES = [
  "saddle_source_cancellation",
  "saddle_sink_creation",
  "saddle_source_creation",
  "saddle_sink_cancellation",
  "hopf_supercritical",
  "hopf_subcritical",
] as const;

function clone<T>(x: T): T {
  return JSON.parse(JSON.stringify(x)) as T;
}

export function isPlanar(scene: Scene): boolean {
  return scene.domain.grid !== undefined;
}

// Time of frame j (DESIGN §3).
export function frameTime(scene: Scene, j: number): number {
  const [t0, t1] = scene.time.range;
  const n = scene.time.frames;
  return n > 1 ? t0 + ((t1 - t0) * j) / (n - 1) : t0;
}

// Nearest frame of time t.
export function frameOf(scene: Scene, t: number): number {
  const [t0, t1] = scene.time.range;
  const n = scene.time.frames;
  if (n <= 1 || t1 === t0) return 0;
  return Math.min(n - 1, Math.max(0, Math.round(((t - t0) / (t1 - t0)) * (n - 1))));
}

// An empty design on the paper's 65×65 grid over [−1, 1]², 100 frames, with the
// spatio-temporal generator (paper §6.1): it keeps every element at its place with its
// type, as the constrained generator does, and it is temporally coherent by
// construction (one solve over space and time: no frame-to-frame flips) and fast (a change's
// picture in about 0.1–0.17 s on two idle cores; docs/benchmarks.md, "Issue 15: every target
// in one idle hour"). The basis sum is faster still but lets wide elements shift each other.
export function emptyScene(): Scene {
  return {
    tvf: 1,
    description: "designed in the browser (tvf serve)",
    domain: { grid: { size: [65, 65], min: [-1, -1], max: [1, 1] } },
    time: { frames: 100, range: [0, 1] },
    generator: "spacetime",
    falloff: 8,
    elements: [],
    keyframes: [],
    edits: [],
  };
}

// A singular element: one point (fixed for the whole time) or a straight path from `from`
// at ts to `to` at te.
export function addSingular(scene: Scene, type: string, from: Vec, to?: Vec, ts?: number, te?: number): Scene {
  const s = clone(scene);
  const path = to && ts !== undefined && te !== undefined && te > ts ? [[...from, ts], [...to, te]] : [[...from, ts ?? s.time.range[0]]];
  (s.elements ??= []).push({ kind: "singular", type, path });
  return s;
}

// A singular element moving along a dragged curve: its points (a few, thinned from the
// drag: stroke.ts's resample), spread evenly in time from ts to te. One point, or
// te <= ts: fixed at the first point.
export function addSingularPath(scene: Scene, type: string, points: Vec[], ts: number, te: number): Scene {
  if (points.length < 2 || !(te > ts)) return addSingular(scene, type, points[0], undefined, ts);
  const s = clone(scene);
  const n = points.length;
  const path = points.map((p, i) => [...p, Math.round((ts + ((te - ts) * i) / (n - 1)) * 1e6) / 1e6]);
  (s.elements ??= []).push({ kind: "singular", type, path });
  return s;
}

// A regular element along a drawn pathline: the drawn points, spread evenly in time from
// ts to te (needs te > ts and at least two points).
export function addPathline(scene: Scene, points: Vec[], ts: number, te: number, attach = 0): Scene {
  if (points.length < 2) throw new Error("a pathline needs at least two points");
  if (!(te > ts)) throw new Error("a pathline needs an end time after its start time");
  const s = clone(scene);
  const n = points.length;
  const pathline = points.map((p, i) => [...p, ts + ((te - ts) * i) / (n - 1)]);
  const e: RegularElement = { kind: "regular", pathline };
  if (attach > 0) e.attach = attach;
  (s.elements ??= []).push(e);
  return s;
}

// A regular element along a pathline whose points carry their own times ([x, y, t] or
// [x, y, z, t], e.g. drawn in the space-time view): at least two points, in strictly
// increasing t inside the time range.
export function addTimedPathline(scene: Scene, pathline: Vec[], attach = 0): Scene {
  if (pathline.length < 2) throw new Error("a pathline needs at least two points");
  const [t0, t1] = scene.time.range;
  pathline.forEach((p, i) => {
    const t = p[p.length - 1];
    if (!(t >= t0 - 1e-9 && t <= t1 + 1e-9)) throw new Error(`pathline point ${i}: t = ${t} is outside the time range [${t0}, ${t1}]`);
    if (i > 0 && !(t > pathline[i - 1][p.length - 1])) throw new Error(`pathline point ${i}: t = ${t} does not come after the point before it`);
  });
  const s = clone(scene);
  const e: RegularElement = { kind: "regular", pathline: pathline.map((p) => [...p]) };
  if (attach > 0) e.attach = attach;
  (s.elements ??= []).push(e);
  return s;
}

export function addBifurcation(scene: Scene, type: string, at: Vec, t: number, scale = 0.25, angle = 0, timeScale = 0.25): Scene {
  const s = clone(scene);
  (s.elements ??= []).push({ kind: "bifurcation", type, at: [...at, t], scale, time_scale: timeScale, angle });
  return s;
}

// A bifurcation's scale and angle from a drag: `coords` the drag's end in the chart
// around its start ([u, v]: on grids the difference, on surfaces the server's log map,
// api.chartCoordinates). The pair moves along the drag, as far apart as it is long (at
// least 0.05); a click (no drag) is the defaults, `clickScale` (0.25 unless given) along +x.
export function bifurcationAxis(coords?: number[], clickScale = 0.25): { scale: number; angle: number } {
  if (!coords) return { scale: clickScale, angle: 0 };
  const r = Math.hypot(coords[0], coords[1]);
  return { scale: Math.max(0.05, Math.round(r * 1000) / 1000), angle: Math.round(Math.atan2(coords[1], coords[0]) * 1000) / 1000 };
}

// The key frame at time t (snapped to its frame), created when missing. Key frames need
// the spatio-temporal generator (paper §6.1), so the scene switches to it.
function keyframeAt(s: Scene, t: number): Keyframe {
  const j = frameOf(s, t);
  s.keyframes ??= [];
  let k = s.keyframes.find((kf) => frameOf(s, kf.t) === j);
  if (!k) {
    k = { t: frameTime(s, j), elements: [] };
    s.keyframes.push(k);
    s.keyframes.sort((a, b) => a.t - b.t);
  }
  if (s.generator !== "spacetime") s.generator = "spacetime";
  return k;
}

export function addKeyframeSingular(scene: Scene, t: number, type: string, at: Vec): Scene {
  const s = clone(scene);
  const before = [...(s.keyframes ?? [])];
  (keyframeAt(s, t).elements ??= []).push({ kind: "singular", type, at: [...at] });
  keepKeyframeTopology(s, before);
  return s;
}

// ---- topology between key frames (solver.keyframe_topology, DESIGN §12) -----------------

// A link of solver.links: keyframes[from[0]].elements[from[1]] is carried into
// keyframes[to[0]].elements[to[1]], to[0] = from[0] + 1.
export interface KeyframeLink {
  from: [number, number];
  to: [number, number];
}

export function keyframeTopologyMatched(scene: Scene): boolean {
  return scene.solver?.keyframe_topology === "matched";
}
export function keyframeLinks(scene: Scene): KeyframeLink[] {
  return keyframeTopologyMatched(scene) ? ((scene.solver?.links as KeyframeLink[] | undefined) ?? []) : [];
}

// Drops the keys that "matched" alone takes (the engine refuses them otherwise).
function dropKeyframeTopology(s: Scene) {
  if (!s.solver) return;
  for (const key of ["keyframe_topology", "links", "bifurcation_times", "path_separation"]) delete s.solver[key];
  if (Object.keys(s.solver).length === 0) delete s.solver;
}

// After the key frames changed (one added, one removed, an element removed): the links
// follow their elements (`before`: the key-frame objects before the change, the same
// objects after it where they stayed), links to what is gone are dropped, the
// per-interval bifurcation times are dropped when the intervals changed, and "matched" is
// dropped when fewer than two key frames are left or the generator is not spacetime.
// `removed`: a key-frame element taken out ([key frame, element] in `before`'s indices).
function keepKeyframeTopology(s: Scene, before: Keyframe[], removed?: [number, number]) {
  if (!keyframeTopologyMatched(s)) return;
  const after = s.keyframes ?? [];
  if (after.length < 2 || s.generator !== "spacetime") return dropKeyframeTopology(s);
  const solver = s.solver!;
  const moved = (end: [number, number]): [number, number] | undefined => {
    const [k, i] = end;
    if (removed && removed[0] === k && removed[1] === i) return undefined;
    const key = after.indexOf(before[k]);
    if (key < 0) return undefined;
    return [key, removed && removed[0] === k && i > removed[1] ? i - 1 : i];
  };
  const links: KeyframeLink[] = [];
  for (const l of (solver.links as KeyframeLink[] | undefined) ?? []) {
    const from = moved(l.from), to = moved(l.to);
    if (from && to && to[0] === from[0] + 1) links.push({ from, to });
  }
  if (links.length) solver.links = links;
  else delete solver.links;
  if (after.length !== before.length) delete solver.bifurcation_times;
}

// Inserts the key frame the engine offers where its guide leaves a node turning (status
// keyframe_intervals[i].middle_keyframe, docs/serve_api.md) between keyframes[before] and
// the next: `from[i]` and `to[i]` are the elements of those two that its element i is
// carried from and to. A link between them through element i is kept as two links through
// it (any other link across the new key frame is dropped, as for any added key frame).
// Refused where the key frames no longer leave room for it (the design changed since).
export function insertMiddleKeyframe(scene: Scene, before: number, key: Keyframe, from: number[], to: number[]): Scene {
  const s = clone(scene);
  const keys = s.keyframes ?? [];
  const j = frameOf(s, key.t);
  if (before + 1 >= keys.length || !(keys[before].t < key.t && key.t < keys[before + 1].t) || keys.some((k) => frameOf(s, k.t) === j))
    throw new Error(`the key frames changed: there is no room for a key frame at t = ${key.t.toFixed(3)} between keyframes[${before}] and the next`);
  const old = [...keys];
  const through = keyframeLinks(s).filter((l) => l.from[0] === before);
  keys.splice(before + 1, 0, clone(key));
  s.keyframes = keys;
  keepKeyframeTopology(s, old);
  const links: KeyframeLink[] = [];
  from.forEach((e, i) => {
    if (to[i] >= 0 && through.some((l) => l.from[1] === e && l.to[1] === to[i]))
      links.push({ from: [before, e], to: [before + 1, i] }, { from: [before + 1, i], to: [before + 2, to[i]] });
  });
  if (links.length) s.solver = { ...(s.solver ?? {}), links: [...((s.solver?.links as KeyframeLink[] | undefined) ?? []), ...links] };
  return s;
}

// Keeps the topology between key frames (or not): with `on`, the spacetime generator
// matches the singularities of consecutive key frames and carries them (solver
// "keyframe_topology": "matched"); off, the solve alone (the paper's behaviour).
export function setKeyframeTopology(scene: Scene, on: boolean): Scene {
  const s = clone(scene);
  if (!on) {
    dropKeyframeTopology(s);
    return s;
  }
  const n = s.keyframes?.length ?? 0;
  if (n < 2)
    throw new Error(
      `keeping the topology between key frames needs two key frames at least (the design has ${n}): place singular elements with "key frame" checked at two times first`,
    );
  s.generator = "spacetime";
  s.solver = { ...(s.solver ?? {}), keyframe_topology: "matched" };
  return s;
}

// The same generator change, without the keys only the spacetime generator takes.
export function setGenerator(scene: Scene, generator: string): Scene {
  const s = clone(scene);
  s.generator = generator;
  if (generator !== "spacetime") dropKeyframeTopology(s);
  return s;
}

// Links two key-frame singular elements of consecutive key frames (picked in either
// order): the one of the earlier key frame is carried into the other, whatever is nearest
// (solver.links). The earlier one's link into that key frame and the later one's link from
// it are replaced; a middle key frame's element keeps its link on the other side (a chain
// k − 1 → k → k + 1). Turns "matched" on.
export function linkKeyframeElements(scene: Scene, a: Handle, b: Handle): Scene {
  if (a.kind !== "keyframe" || b.kind !== "keyframe") throw new Error("links join key-frame elements: pick a square of a key frame");
  const [p, q] = a.key <= b.key ? [a, b] : [b, a];
  if (q.key !== p.key + 1)
    throw new Error(
      p.key === q.key
        ? "both are in the same key frame: go to the next (or previous) key frame and pick the partner there"
        : `these are in key frames ${p.key} and ${q.key}; a link joins a key frame with the next one`,
    );
  const ep = scene.keyframes?.[p.key]?.elements?.[p.index];
  const eq = scene.keyframes?.[q.key]?.elements?.[q.index];
  if (!ep || !eq) throw new Error("no such key-frame element");
  if (ep.kind !== "singular" || eq.kind !== "singular") throw new Error("only singular elements are linked");
  // As the engine checks it: the same type, or where a Jacobian is given the same index.
  const index = (e: KeyframeElement) => (e.type ? (e.type === "saddle" ? -1 : 1) : det(e.jacobian) < 0 ? -1 : 1);
  const same = ep.type && eq.type ? ep.type === eq.type : index(ep) === index(eq);
  if (!same)
    throw new Error(`a ${ep.type ?? "Jacobian"} cannot be linked with a ${eq.type ?? "Jacobian"}: linked singularities have the same type`);
  const s = setKeyframeTopology(scene, true);
  const solver = s.solver!;
  const replaced = (l: KeyframeLink) =>
    (l.from[0] === p.key && l.from[1] === p.index) || (l.to[0] === q.key && l.to[1] === q.index);
  const links = ((solver.links as KeyframeLink[] | undefined) ?? []).filter((l) => !replaced(l));
  links.push({ from: [p.key, p.index], to: [q.key, q.index] });
  solver.links = links;
  return s;
}

function det(m?: number[][]): number {
  return m ? m[0][0] * m[1][1] - m[0][1] * m[1][0] : 1;
}

// A streakline sketched at time t (the drawn curve from the seed), its dye released over
// the half of the time range before t (from the range's start at most). The basis
// generator leaves streaklines out, so a basis design becomes a spacetime one.
export function addStreakline(scene: Scene, points: Vec[], t: number): Scene {
  if (points.length < 2) throw new Error("a streakline needs at least two points");
  const [t0, t1] = scene.time?.range ?? [0, 1];
  const from = Number(Math.max(t0, t - 0.5 * (t1 - t0)).toFixed(4));
  if (!(from < t)) throw new Error("a streakline is sketched at a time after the start of the time range: move the time slider on");
  const s = clone(scene);
  if (!s.generator || s.generator === "basis") s.generator = "spacetime";
  (s.elements ??= []).push({ kind: "streakline", points: points.map((p) => [...p]), t, from });
  return s;
}

export function addKeyframeStreamline(scene: Scene, t: number, points: Vec[]): Scene {
  if (points.length < 2) throw new Error("a streamline needs at least two points");
  const s = clone(scene);
  const before = [...(s.keyframes ?? [])];
  (keyframeAt(s, t).streamlines ??= []).push({ points: points.map((p) => [...p]) });
  keepKeyframeTopology(s, before);
  return s;
}

// What can be picked and moved on the canvas at a time t.
export type Handle =
  | { kind: "element"; index: number; point: number } // elements[index], its path/pathline point or `at`
  | { kind: "keyframe"; key: number; index: number }; // keyframes[key].elements[index]

// Position on a path of control points [x, y, t] (or [x, y, z, t]) at time t, as the
// engine moves elements (src/design/hermite_path.cpp): piecewise cubic Hermite in t with
// Catmull–Rom tangents m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1}), one-sided at the
// ends; t is clamped to the path's time span.
export function hermitePosition(path: Vec[], t: number): Vec {
  const n = path.length;
  const d = path[0].length - 1;
  const tt = (i: number) => path[i][d];
  const pos = (i: number) => path[i].slice(0, d);
  if (n === 1) return pos(0);
  t = Math.min(Math.max(t, tt(0)), tt(n - 1));
  const tangent = (i: number) => {
    const a = i === 0 ? 0 : i - 1;
    const b = i + 1 === n ? n - 1 : i + 1;
    const dt = tt(b) - tt(a);
    return pos(b).map((v, k) => (v - path[a][k]) / dt);
  };
  // Last point with t_i <= t, limited to the last segment's start.
  let i = 0;
  while (i + 1 < n && tt(i + 1) <= t) ++i;
  i = Math.min(i, n - 2);
  const h = tt(i + 1) - tt(i);
  const s = (t - tt(i)) / h;
  const s2 = s * s;
  const s3 = s2 * s;
  const h00 = 2 * s3 - 3 * s2 + 1;
  const h10 = s3 - 2 * s2 + s;
  const h01 = -2 * s3 + 3 * s2;
  const h11 = s3 - s2;
  const ma = tangent(i);
  const mb = tangent(i + 1);
  return pos(i).map((v, k) => h00 * v + h10 * h * ma[k] + h01 * path[i + 1][k] + h11 * h * mb[k]);
}

// Position of a singular element at time t, on the engine's path (hermitePosition), or
// undefined outside its life span.
export function singularPosition(e: SingularElement, t: number): Vec | undefined {
  const p = e.path;
  if (p.length === 1) return p[0].slice(0, -1);
  const tt = (q: Vec) => q[q.length - 1];
  if (t < tt(p[0]) - 1e-9 || t > tt(p[p.length - 1]) + 1e-9) return undefined;
  return hermitePosition(p, t);
}

// Handles visible at time t with their positions.
export function handles(scene: Scene, t: number): { handle: Handle; position: Vec }[] {
  const out: { handle: Handle; position: Vec }[] = [];
  (scene.elements ?? []).forEach((e, index) => {
    if (e.kind === "singular") {
      // The control point nearest in time is the one a drag moves.
      let best = 0;
      e.path.forEach((q, i) => {
        if (Math.abs(q[q.length - 1] - t) < Math.abs(e.path[best][e.path[best].length - 1] - t)) best = i;
      });
      const pos = e.path.length === 1 ? e.path[0].slice(0, -1) : singularPosition(e, t);
      if (pos) out.push({ handle: { kind: "element", index, point: best }, position: pos });
    } else if (e.kind === "regular") {
      e.pathline.forEach((q, point) => out.push({ handle: { kind: "element", index, point }, position: q.slice(0, -1) }));
    } else if (e.kind === "streakline") {
      e.points.forEach((q, point) => out.push({ handle: { kind: "element", index, point }, position: [...q] }));
    } else {
      out.push({ handle: { kind: "element", index, point: 0 }, position: e.at.slice(0, -1) });
    }
  });
  const j = frameOf(scene, t);
  (scene.keyframes ?? []).forEach((k, key) => {
    if (frameOf(scene, k.t) !== j) return;
    (k.elements ?? []).forEach((e, index) => out.push({ handle: { kind: "keyframe", key, index }, position: e.at }));
  });
  return out;
}

// The handle nearest to p within `radius` (world units), if any.
export function pick(scene: Scene, t: number, p: Vec, radius: number): Handle | undefined {
  let best: Handle | undefined;
  let bestD = radius;
  for (const h of handles(scene, t)) {
    const d = Math.hypot(...h.position.map((v, k) => v - p[k]));
    if (d <= bestD) {
      bestD = d;
      best = h.handle;
    }
  }
  return best;
}

// Moves a handle to p. A singular element with one point moves; one with a path moves the
// control point nearest in time; a pathline point or a bifurcation moves in space only.
export function moveHandle(scene: Scene, h: Handle, p: Vec): Scene {
  const s = clone(scene);
  if (h.kind === "keyframe") {
    const e = s.keyframes?.[h.key]?.elements?.[h.index];
    if (e) e.at = [...p];
    return s;
  }
  const e = s.elements?.[h.index];
  if (!e) return s;
  if (e.kind === "singular") {
    const q = e.path[h.point];
    e.path[h.point] = [...p, q[q.length - 1]];
  } else if (e.kind === "regular") {
    const q = e.pathline[h.point];
    e.pathline[h.point] = [...p, q[q.length - 1]];
  } else if (e.kind === "streakline") {
    e.points[h.point] = [...p];
  } else {
    e.at = [...p, e.at[e.at.length - 1]];
  }
  return s;
}

// Removes what a handle names (a whole element, or a key-frame element; a key frame left
// with nothing in it is removed too).
export function removeHandle(scene: Scene, h: Handle): Scene {
  const s = clone(scene);
  if (h.kind === "element") {
    s.elements?.splice(h.index, 1);
  } else {
    const before = [...(s.keyframes ?? [])];
    const k = s.keyframes?.[h.key];
    k?.elements?.splice(h.index, 1);
    if (k && !(k.elements?.length) && !(k.streamlines?.length) && !k.field) s.keyframes?.splice(h.key, 1);
    keepKeyframeTopology(s, before, [h.key, h.index]);
  }
  return s;
}

// The edit entries of DESIGN §7 the view sends (positions as the domain writes them).
export function cancelEdit(frame: number, a: Vec, b: Vec) {
  return { op: "cancel", frame, pair: [a, b] };
}
export function removeBifurcationEdit(position: Vec, t: number) {
  return { op: "remove_bifurcation", at: [...position, t] };
}
export function moveBifurcationEdit(position: Vec, t: number, to: Vec, t2: number) {
  return { op: "move_bifurcation", at: [...position, t], to: [...to, t2] };
}

// Field deformation (paper §7, the deform generator): the design so far becomes the base
// field V(t0) (its elements move into deform.base; key frames are not part of it).
function toDeform(s: Scene): NonNullable<DeformBlock> {
  if (s.generator !== "deform" || !s.deform) {
    s.deform = { base: { elements: s.elements ?? [] }, streamlines: [] };
    s.elements = [];
    s.generator = "deform";
  }
  return s.deform as DeformBlock;
}
export interface DeformBlock {
  base: { elements: Element[] };
  matrix?: unknown[];
  transform?: { t: number; sx: number; sy: number; theta: number }[];
  streamlines?: { seed: Vec; keys: { t: number; translate: Vec; rotate: number; scale: number }[] }[];
}

// A representative streamline (traced in V(t0) from `seed`) moved by `translate` and
// turned by `rotate` radians by time t (> the first time; keys of one streamline stay in
// increasing t: a key at the same frame is replaced).
export function addDeformStreamline(scene: Scene, seed: Vec, translate: Vec, t: number, rotate = 0, scale = 1): Scene {
  if (!(t > scene.time.range[0])) throw new Error("move the time past the start: a deformation key needs t after the first frame");
  const s = clone(scene);
  const d = toDeform(s);
  d.streamlines ??= [];
  const key = { t, translate: [...translate], rotate, scale };
  const near = d.streamlines.find((sl) => Math.hypot(...sl.seed.map((v, k) => v - seed[k])) < 1e-6);
  if (near) {
    near.keys = near.keys.filter((k) => frameOf(s, k.t) !== frameOf(s, t));
    near.keys.push(key);
    near.keys.sort((a, b) => a.t - b.t);
  } else {
    d.streamlines.push({ seed: [...seed], keys: [key] });
  }
  return s;
}

// Where the deformation's representative streamlines start (their seeds) and, on planar
// domains, where each key puts the seed (seed + translate; on surfaces the translate is a
// tangent vector of the seed's log-map chart, so its end is not a point of the surface).
export function deformSeeds(scene: Scene): Vec[] {
  const d = scene.generator === "deform" ? (scene.deform as DeformBlock | undefined) : undefined;
  return (d?.streamlines ?? []).map((sl) => [...sl.seed]);
}

// The whole field turned by theta radians (and scaled by sx, sy) from the first time to
// the last: M(t) keys of the deform generator (sx, sy, θ interpolated linearly).
export function setDeformTransform(scene: Scene, theta: number, sx = 1, sy = 1): Scene {
  const s = clone(scene);
  const d = toDeform(s);
  const [t0, t1] = s.time.range;
  delete d.matrix;
  d.transform = [
    { t: t0, sx: 1, sy: 1, theta: 0 },
    { t: t1, sx, sy, theta },
  ];
  return s;
}

// The mean edge length of a mesh given as flat vertex and face arrays (each edge counted
// once per face using it, as the server's mean over the faces' edges).
export function meanEdgeLength(vertices: number[], faces: number[]): number {
  let sum = 0;
  for (let f = 0; f + 2 < faces.length; f += 3)
    for (let k = 0; k < 3; ++k) {
      const a = 3 * faces[f + k], b = 3 * faces[f + ((k + 1) % 3)];
      sum += Math.hypot(vertices[a] - vertices[b], vertices[a + 1] - vertices[b + 1], vertices[a + 2] - vertices[b + 2]);
    }
  return faces.length >= 3 ? sum / faces.length : 0;
}

// A clicked bifurcation's scale: 0.25, or for a Hopf template at least seven mean edge
// lengths (the analysis resolves its event from about six: a click on the default sphere,
// 0.25 = 3.3 edge lengths, made a template whose event was never found).
export function clickedBifurcationScale(type: string, meanEdge: number): number {
  return type.startsWith("hopf") ? Math.max(0.25, Math.round(7 * meanEdge * 1000) / 1000) : 0.25;
}
