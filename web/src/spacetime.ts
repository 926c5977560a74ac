// The space-time view (paper Fig. 2): the domain's rectangle stretched along a time axis,
// singularity paths as curves coloured by type, bifurcations as spheres (Hopf events too),
// periodic orbits as loops at their times (attracting orange, repelling teal), the design's
// pathlines (regular elements) as thick teal curves, and the current time as a plane. A
// click on a bifurcation picks it (for removal or moving). With `drawing` on (the
// Pathline tool), a drag that starts on the time plane inside the domain draws a pathline
// (spacetime_draw.ts says how the 2-D drag becomes an (x, y, t) curve); any other drag
// orbits.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { Analysis } from "./api";
import { BIFURCATION_COLOR, PATHLINE_COLOR, typeColor } from "./colors";
import { orbitColor } from "./orbits";
import { intersect, timePlane, uprightPlane, type Plane, type Ray, type V3 } from "./spacetime_draw";
import { formatTicks, niceTicks } from "./ticks";

// A label that always faces the camera: text drawn on a canvas texture.
function textSprite(text: string, height = 0.14): THREE.Sprite {
  const c = document.createElement("canvas");
  const px = 40;
  const ctx = c.getContext("2d")!;
  ctx.font = `${px}px sans-serif`;
  c.width = Math.ceil(ctx.measureText(text).width) + 8;
  c.height = px + 12;
  ctx.font = `${px}px sans-serif`;
  ctx.fillStyle = "#0f172a";
  ctx.textBaseline = "middle";
  ctx.fillText(text, 4, c.height / 2);
  const texture = new THREE.CanvasTexture(c);
  texture.minFilter = THREE.LinearFilter;
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, depthTest: false, transparent: true }));
  sprite.scale.set((height * c.width) / c.height, height, 1);
  sprite.renderOrder = 3;
  return sprite;
}

export class SpaceTimeView {
  private readonly renderer: THREE.WebGLRenderer;
  private readonly scene = new THREE.Scene();
  private readonly camera: THREE.PerspectiveCamera;
  private readonly controls: OrbitControls;
  private readonly content = new THREE.Group();
  private readonly plane: THREE.Mesh;
  private bifurcationMeshes: THREE.Mesh[] = [];
  private min: [number, number] = [-1, -1];
  private max: [number, number] = [1, 1];
  private range: [number, number] = [0, 1];
  private selected = -1;
  private time = 0;
  private readonly design = new THREE.Group();
  private readonly strokeLine: THREE.Line;
  private stroke: { plane: Plane; points: number[][]; id: number } | undefined;
  private drewAt = -1e9; // when the last drawn stroke ended (performance.now())
  private pathlines: number[][][] = [];
  onPick: (index: number) => void = () => {};
  // The Pathline tool: drags from the time plane draw; onStroke gets world [x, y, t] points.
  drawing = false;
  onStroke: (points: number[][]) => void = () => {};

  constructor(host: HTMLElement) {
    const w = host.clientWidth || 360;
    const h = host.clientHeight || 300;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setSize(w, h);
    this.renderer.setClearColor(0xffffff);
    host.appendChild(this.renderer.domElement);
    // Registered before OrbitControls' own listener, so that a drawing drag can switch the
    // orbit off before it starts.
    const el = this.renderer.domElement;
    el.addEventListener("pointerdown", (ev) => this.strokeStart(ev));
    el.addEventListener("pointermove", (ev) => this.strokeMove(ev));
    el.addEventListener("pointerup", (ev) => this.strokeEnd(ev));
    el.addEventListener("pointercancel", () => this.strokeCancel());
    this.camera = new THREE.PerspectiveCamera(35, w / h, 0.01, 100);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(3.6, -4.4, 3.4);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 0.9);
    this.controls.update();
    this.controls.addEventListener("change", () => this.render());
    this.scene.add(this.content);
    this.plane = new THREE.Mesh(
      new THREE.PlaneGeometry(2, 2),
      new THREE.MeshBasicMaterial({ color: 0x94a3b8, transparent: true, opacity: 0.25, side: THREE.DoubleSide, depthWrite: false }),
    );
    this.scene.add(this.plane);
    this.scene.add(this.design);
    this.strokeLine = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xf97316, depthTest: false }));
    this.strokeLine.renderOrder = 2;
    this.scene.add(this.strokeLine);
    this.renderer.domElement.addEventListener("click", (ev) => this.click(ev));
    this.render();
  }

  // World (x, y, t) → view coordinates: the domain fitted into [−1, 1]², t into [0, 2].
  private map(x: number, y: number, t: number): THREE.Vector3 {
    const s = 2 / Math.max(this.max[0] - this.min[0], this.max[1] - this.min[1]);
    const cx = (this.min[0] + this.max[0]) / 2;
    const cy = (this.min[1] + this.max[1]) / 2;
    const tt = this.range[1] > this.range[0] ? (2 * (t - this.range[0])) / (this.range[1] - this.range[0]) : 0;
    return new THREE.Vector3((x - cx) * s, (y - cy) * s, tt);
  }

  // View coordinates → world (x, y, t): the inverse of map.
  private unmap(v: V3): number[] {
    const s = 2 / Math.max(this.max[0] - this.min[0], this.max[1] - this.min[1]);
    const cx = (this.min[0] + this.max[0]) / 2;
    const cy = (this.min[1] + this.max[1]) / 2;
    return [v[0] / s + cx, v[1] / s + cy, this.range[0] + (v[2] / 2) * (this.range[1] - this.range[0])];
  }

  // Page-independent canvas pixel position of a world (x, y, t) point (for tests).
  toScreen(p: number[]): [number, number] {
    const v = this.map(p[0], p[1], p[2]).project(this.camera);
    const c = this.renderer.domElement;
    return [((v.x + 1) / 2) * c.clientWidth, ((1 - v.y) / 2) * c.clientHeight];
  }

  // The time axis' labels: [text, screen position] (for tests).
  timeLabels(): { t: number; at: [number, number] }[] {
    return this.content.children
      .filter((c) => c.userData.tick !== undefined)
      .map((c) => {
        const v = c.position.clone().project(this.camera);
        const el = this.renderer.domElement;
        return { t: c.userData.tick as number, at: [((v.x + 1) / 2) * el.clientWidth, ((1 - v.y) / 2) * el.clientHeight] as [number, number] };
      });
  }

  // The design's pathlines (each a list of [x, y, t] points), drawn over the paths.
  setDesign(pathlines: number[][][]) {
    this.pathlines = pathlines;
    this.drawDesign();
  }

  private drawDesign() {
    const pathlines = this.pathlines;
    for (const child of [...this.design.children]) {
      this.design.remove(child);
      (child as THREE.Mesh).geometry?.dispose();
    }
    for (const line of pathlines) {
      if (line.length < 2) continue;
      const pts = line.map((p) => this.map(p[0], p[1], p[p.length - 1]));
      const curve = new THREE.CatmullRomCurve3(pts, false, "catmullrom", 0.5);
      const tube = new THREE.Mesh(new THREE.TubeGeometry(curve, 8 * pts.length, 0.018, 6, false), new THREE.MeshBasicMaterial({ color: PATHLINE_COLOR }));
      this.design.add(tube);
      for (const p of pts) {
        const dot = new THREE.Mesh(new THREE.SphereGeometry(0.03, 10, 8), new THREE.MeshBasicMaterial({ color: PATHLINE_COLOR }));
        dot.position.copy(p);
        this.design.add(dot);
      }
    }
    this.render();
  }

  private ray(ev: PointerEvent | MouseEvent): Ray {
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const o = ray.ray.origin;
    const d = ray.ray.direction;
    return { origin: [o.x, o.y, o.z], direction: [d.x, d.y, d.z] };
  }

  private strokeStart(ev: PointerEvent) {
    if (!this.drawing || ev.button !== 0) return;
    const z = this.map(0, 0, this.time).z;
    const hit = intersect(this.ray(ev), timePlane(z));
    if (!hit) return;
    const w = this.unmap(hit);
    const inside = w[0] >= this.min[0] && w[0] <= this.max[0] && w[1] >= this.min[1] && w[1] <= this.max[1];
    if (!inside) return; // a drag outside the domain orbits
    const view = new THREE.Vector3();
    this.camera.getWorldDirection(view);
    const plane = uprightPlane(hit, [view.x, view.y, view.z]);
    if (!plane) return;
    this.controls.enabled = false;
    this.renderer.domElement.setPointerCapture(ev.pointerId);
    this.stroke = { plane, points: [[w[0], w[1], this.time]], id: ev.pointerId };
    this.showStroke();
  }

  private strokeMove(ev: PointerEvent) {
    if (!this.stroke || ev.pointerId !== this.stroke.id) return;
    const hit = intersect(this.ray(ev), this.stroke.plane);
    if (!hit) return;
    this.stroke.points.push(this.unmap(hit));
    this.showStroke();
  }

  private strokeEnd(ev: PointerEvent) {
    if (!this.stroke || ev.pointerId !== this.stroke.id) return;
    this.strokeMove(ev);
    const points = this.stroke.points;
    this.strokeCancel();
    this.drewAt = performance.now();
    this.onStroke(points);
  }

  private strokeCancel() {
    this.stroke = undefined;
    this.controls.enabled = true;
    this.showStroke();
  }

  private showStroke() {
    const pts = (this.stroke?.points ?? []).map((p) => this.map(p[0], p[1], p[2]));
    this.strokeLine.geometry.dispose();
    this.strokeLine.geometry = new THREE.BufferGeometry().setFromPoints(pts);
    this.render();
  }

  set(analysis: Analysis, min: [number, number], max: [number, number], range: [number, number]) {
    this.min = min;
    this.max = max;
    this.range = range;
    for (const child of [...this.content.children]) {
      this.content.remove(child);
      const m = child as THREE.Mesh;
      m.geometry?.dispose();
      const material = m.material as THREE.Material & { map?: THREE.Texture };
      material?.map?.dispose();
      material?.dispose?.();
    }
    // The domain's rectangle at the first and last time, and its corners' edges.
    const corners = [
      [min[0], min[1]],
      [max[0], min[1]],
      [max[0], max[1]],
      [min[0], max[1]],
    ];
    const box: THREE.Vector3[] = [];
    for (const t of range)
      for (let k = 0; k < 4; ++k) box.push(this.map(corners[k][0], corners[k][1], t), this.map(corners[(k + 1) % 4][0], corners[(k + 1) % 4][1], t));
    for (const c of corners) box.push(this.map(c[0], c[1], range[0]), this.map(c[0], c[1], range[1]));
    this.content.add(new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(box), new THREE.LineBasicMaterial({ color: 0x94a3b8 })));
    // The time axis: ticks and labels along the edge nearest the camera, and its name.
    const ticks = niceTicks(range[0], range[1], 5);
    const labels = formatTicks(ticks);
    const edge = [max[0], min[1]];
    const out = this.map(edge[0], edge[1], range[0]).clone().normalize().setZ(0).multiplyScalar(0.06);
    const marks: THREE.Vector3[] = [];
    ticks.forEach((t, k) => {
      const at = this.map(edge[0], edge[1], t);
      marks.push(at, at.clone().add(out));
      const label = textSprite(labels[k]);
      label.position.copy(at.clone().add(out.clone().multiplyScalar(3.2)));
      label.userData.tick = t;
      this.content.add(label);
    });
    this.content.add(new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(marks), new THREE.LineBasicMaterial({ color: 0x334155 })));
    const name = textSprite("t", 0.18);
    name.position.copy(this.map(edge[0], edge[1], range[1]).add(out.clone().multiplyScalar(3.2)).add(new THREE.Vector3(0, 0, 0.22)));
    this.content.add(name);
    for (const path of analysis.paths) {
      const pts = path.points.map((p) => this.map(p[0], p[1], p[3]));
      if (pts.length < 2) continue;
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: typeColor(path.type) }));
      this.content.add(line);
    }
    // Periodic orbits: each track at about twelve evenly spaced frames, as loops at their t.
    const tracks = new Map<number, NonNullable<Analysis["periodic_orbits"]>>();
    for (const o of analysis.periodic_orbits ?? []) {
      if (!tracks.has(o.id)) tracks.set(o.id, []);
      tracks.get(o.id)!.push(o);
    }
    for (const list of tracks.values()) {
      const stride = Math.max(1, Math.ceil(list.length / 12));
      for (let k = 0; k < list.length; k += stride) {
        const o = list[k];
        const pts = o.points.map((p) => this.map(p[0], p[1], o.t));
        const color = new THREE.Color(orbitColor(o));
        this.content.add(new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color })));
      }
    }
    this.bifurcationMeshes = analysis.bifurcations.map((b, i) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.05, 16, 12), new THREE.MeshBasicMaterial({ color: BIFURCATION_COLOR }));
      m.position.copy(this.map(b.position[0], b.position[1], b.t));
      m.userData.index = i;
      this.content.add(m);
      return m;
    });
    this.drawDesign();
    this.highlight(this.selected);
  }

  setTime(t: number) {
    this.time = t;
    const z = this.map(0, 0, t).z;
    const s = 2 / Math.max(this.max[0] - this.min[0], this.max[1] - this.min[1]);
    this.plane.scale.set((this.max[0] - this.min[0]) * s / 2, (this.max[1] - this.min[1]) * s / 2, 1);
    this.plane.position.set(0, 0, z);
    this.render();
  }

  highlight(index: number) {
    this.selected = index;
    this.bifurcationMeshes.forEach((m, i) => {
      (m.material as THREE.MeshBasicMaterial).color.set(i === index ? 0x111827 : BIFURCATION_COLOR);
      m.scale.setScalar(i === index ? 1.6 : 1);
    });
    this.render();
  }

  private click(ev: MouseEvent) {
    if (performance.now() - this.drewAt < 400) return; // the click that ends a drawn stroke picks nothing
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const hit = ray.intersectObjects(this.bifurcationMeshes)[0];
    if (hit) this.onPick(hit.object.userData.index as number);
  }

  // Draws on the next animation frame; calls before it coalesce (playing the timeline
  // moves the time plane every frame, and a software-GL browser draws slowly).
  private pending = false;
  render() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      this.renderer.render(this.scene, this.camera);
    });
  }
}
