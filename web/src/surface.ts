// The surface designer's view: the mesh with the current frame's field as a moving
// texture (surface/preview.ts) and/or arrows at a subset of vertices, singularities
// coloured by type, design elements (markers, the singular elements' paths, pathlines and
// key-frame streamlines as thick curves) and the analysis's singularity paths coloured by
// time (surface/paths.ts). A click on the surface reports the picked point [x, y, z] (the
// server snaps positions to the surface). A left drag that starts on the surface belongs
// to the tool when `grab` says so for its first point (drawing tools; the Select tool on
// a control point): every pointer position is picked on the surface, and the stroke's
// points go to onStroke. Other drags orbit; a right drag (or Alt + left drag) always
// orbits, Shift + left drag pans, the wheel zooms. The LCS overlay (lcs.ts) colours the
// mesh per vertex by the FTLE (setFtle; it replaces the moving texture while on) and draws
// the dye's streaklines and timelines as thin tubes on the mesh (setDye).
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { Analysis, Frame, MeshData } from "./api";
import { typeColor, WRONG_PLACE_COLOR } from "./colors";
import { pathObjects } from "./surface/paths";
import { SurfaceTexture } from "./surface/preview";

// What the surface shows of the field: the moving texture, arrows, or both.
export type SurfaceMode = "texture" | "arrows" | "both";

// The FTLE overlay: each vertex's colour (attribute `ftle`, r, g, b in [0, 1]), shaded
// gently by the normal so the shape still reads (the colour's hue and order unchanged).
const ftleVertex = /* glsl */ `
attribute vec3 ftle;
varying vec3 vColor;
varying vec3 vNormal;
void main() {
  vColor = ftle;
  vNormal = normalize(normalMatrix * normal);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
const ftleFragment = /* glsl */ `
varying vec3 vColor;
varying vec3 vNormal;
void main() {
  gl_FragColor = vec4(vColor * (0.75 + 0.25 * abs(normalize(vNormal).z)), 1.0);
}`;

// Takes every child out of a group, freeing its geometry (and its material, where the
// group's children each have their own; the design's and the paths' share theirs).
function emptyGroup(group: THREE.Group, materials: boolean) {
  for (const c of [...group.children]) {
    group.remove(c);
    (c as THREE.Mesh).geometry?.dispose();
    if (materials) ((c as THREE.Mesh).material as THREE.Material | undefined)?.dispose();
  }
}

export class SurfaceView {
  private readonly renderer: THREE.WebGLRenderer;
  private readonly scene = new THREE.Scene();
  private readonly camera: THREE.PerspectiveCamera;
  private readonly controls: OrbitControls;
  private surface: THREE.Mesh | undefined;
  private readonly overlay = new THREE.Group();
  private positions: Float32Array = new Float32Array();
  private radius = 1;
  private down: [number, number] | undefined;
  private readonly design = new THREE.Group();
  private readonly strokeLine: THREE.Line;
  private stroke: { points: number[][]; id: number } | undefined;
  private readonly paths = new THREE.Group();
  private readonly plain = new THREE.MeshStandardMaterial({ color: 0xe8edf3, roughness: 0.9, side: THREE.DoubleSide });
  private readonly texture: SurfaceTexture;
  private readonly ftleMaterial = new THREE.ShaderMaterial({ vertexShader: ftleVertex, fragmentShader: ftleFragment, side: THREE.DoubleSide });
  private ftleOn = false;
  private readonly dye = new THREE.Group();
  private readonly orbits = new THREE.Group();
  private readonly mark = new THREE.Group();
  private markAt: number[][] = [];
  private mode: SurfaceMode = "texture";
  private frame: Frame | undefined;
  private markers: number[][] = [];
  onPick: (p: number[]) => void = () => {};
  // Whether a left drag starting at this point of the surface is the tool's.
  grab: (p: number[]) => boolean = () => false;
  onStroke: (points: number[][]) => void = () => {};

  constructor(host: HTMLElement) {
    const w = host.clientWidth || 512;
    const h = host.clientHeight || 512;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setSize(w, h);
    this.renderer.setClearColor(0xffffff);
    host.appendChild(this.renderer.domElement);
    const el = this.renderer.domElement;
    // Registered before OrbitControls' own listeners, so that a drawing drag can switch
    // the orbit off before it starts.
    el.addEventListener("pointerdown", (e) => this.strokeStart(e));
    el.addEventListener("pointermove", (e) => this.strokeMove(e));
    el.addEventListener("pointercancel", () => this.strokeCancel());
    this.camera = new THREE.PerspectiveCamera(40, w / h, 0.001, 1000);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.mouseButtons = { LEFT: THREE.MOUSE.ROTATE, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.ROTATE };
    el.addEventListener("contextmenu", (e) => e.preventDefault());
    this.controls.addEventListener("change", () => {
      this.texture.invalidate();
      this.render();
    });
    this.texture = new SurfaceTexture(this.renderer);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 3.0));
    this.scene.add(this.overlay);
    this.scene.add(this.design);
    this.scene.add(this.paths);
    this.scene.add(this.dye);
    this.scene.add(this.orbits);
    this.scene.add(this.mark);
    this.strokeLine = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xf97316, depthTest: false }));
    this.strokeLine.renderOrder = 2;
    this.scene.add(this.strokeLine);
    // A click (not a drag of the camera) picks a point.
    el.addEventListener("pointerdown", (e) => (this.down = [e.clientX, e.clientY]));
    el.addEventListener("pointerup", (e) => {
      const click = this.down && Math.hypot(e.clientX - this.down[0], e.clientY - this.down[1]) < 4;
      this.down = undefined;
      if (this.stroke && e.pointerId === this.stroke.id) {
        this.strokeMove(e);
        const points = this.stroke.points;
        this.strokeCancel();
        if (!click) return this.onStroke(points);
      }
      if (click) this.pick(e);
    });
  }

  // The camera as the video should see the mesh: the direction from the mesh's centre
  // to the camera, the screen's up direction, and the vertical field of view (degrees).
  cameraView(): { view: number[]; up: number[]; fov: number } {
    const d = this.camera.position.clone().sub(this.controls.target).normalize();
    const up = new THREE.Vector3(0, 1, 0).applyQuaternion(this.camera.quaternion);
    const r = (v: number) => Math.round(v * 1e4) / 1e4;
    return { view: [r(d.x), r(d.y), r(d.z)], up: [r(up.x), r(up.y), r(up.z)], fov: this.camera.fov };
  }

  // Canvas pixel position of a world point (for tests).
  toScreen(p: number[]): [number, number] {
    const v = new THREE.Vector3(p[0], p[1], p[2]).project(this.camera);
    const c = this.renderer.domElement;
    return [((v.x + 1) / 2) * c.clientWidth, ((1 - v.y) / 2) * c.clientHeight];
  }

  // The design's curves on the surface: pathlines and streamlines, [x, y, z, …] points.
  // `dashed`: a thin dashed line through the control points (the singular elements'
  // paths, so that the analysis's time-coloured path under it stays visible).
  // `ends`: dots at the first and last point only (a link drawn over the surface).
  setDesign(lines: { points: number[][]; color: string; dashed?: boolean; ends?: boolean }[]) {
    emptyGroup(this.design, false);
    for (const line of lines) {
      if (line.points.length < 2) continue;
      const pts = line.points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
      const curve = new THREE.CatmullRomCurve3(pts, false, "catmullrom", 0.5);
      const material = new THREE.MeshBasicMaterial({ color: line.color });
      if (line.dashed) {
        const l = new THREE.Line(
          new THREE.BufferGeometry().setFromPoints(curve.getPoints(8 * pts.length)),
          new THREE.LineDashedMaterial({ color: line.color, dashSize: 0.03 * this.radius, gapSize: 0.02 * this.radius }),
        );
        l.computeLineDistances();
        this.design.add(l);
      } else this.design.add(new THREE.Mesh(new THREE.TubeGeometry(curve, 8 * pts.length, 0.008 * this.radius, 6, false), material));
      for (const p of line.ends ? [pts[0], pts[pts.length - 1]] : pts) {
        const dot = new THREE.Mesh(new THREE.SphereGeometry(0.014 * this.radius, 10, 8), material);
        dot.position.copy(p);
        this.design.add(dot);
      }
    }
    this.render();
  }

  private hit(e: PointerEvent): THREE.Vector3 | undefined {
    if (!this.surface) return undefined;
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    return ray.intersectObject(this.surface)[0]?.point;
  }

  private strokeStart(e: PointerEvent) {
    if (e.button !== 0 || e.altKey || e.shiftKey || e.ctrlKey || e.metaKey) return;
    const p = this.hit(e);
    if (!p || !this.grab([p.x, p.y, p.z])) return; // off the surface, or not the tool's: orbit
    this.controls.enabled = false;
    this.renderer.domElement.setPointerCapture(e.pointerId);
    this.stroke = { points: [[p.x, p.y, p.z]], id: e.pointerId };
    this.showStroke();
  }

  private strokeMove(e: PointerEvent) {
    if (!this.stroke || e.pointerId !== this.stroke.id) return;
    const p = this.hit(e);
    if (!p) return; // off the surface: the stroke waits until the pointer is back on it
    const last = this.stroke.points[this.stroke.points.length - 1];
    if (Math.hypot(p.x - last[0], p.y - last[1], p.z - last[2]) < 0.005 * this.radius) return;
    this.stroke.points.push([p.x, p.y, p.z]);
    this.showStroke();
  }

  private strokeCancel() {
    this.stroke = undefined;
    this.controls.enabled = true;
    this.showStroke();
  }

  private showStroke() {
    const pts = (this.stroke?.points ?? []).map((p) => new THREE.Vector3(p[0], p[1], p[2]));
    this.strokeLine.geometry.dispose();
    this.strokeLine.geometry = new THREE.BufferGeometry().setFromPoints(pts);
    this.render();
  }

  get canvas(): HTMLCanvasElement {
    return this.renderer.domElement;
  }

  setMesh(mesh: MeshData) {
    if (this.surface) {
      this.scene.remove(this.surface);
      this.surface.geometry.dispose();
    }
    this.positions = Float32Array.from(mesh.vertices);
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(this.positions, 3));
    g.setIndex(mesh.faces);
    g.computeVertexNormals();
    g.computeBoundingSphere();
    const s = g.boundingSphere!;
    this.radius = s.radius;
    this.texture.setGeometry(g, s.radius);
    g.setAttribute("ftle", new THREE.BufferAttribute(new Float32Array(this.positions.length), 3));
    this.ftleOn = false;
    this.surface = new THREE.Mesh(g, this.material());
    this.scene.add(this.surface);
    this.markAt = [];
    this.drawMark();
    this.controls.target.copy(s.center);
    this.camera.position.copy(s.center).add(new THREE.Vector3(0.2, -1, 0.6).normalize().multiplyScalar(3 * s.radius));
    this.controls.update();
    this.render();
  }

  // Texture, arrows or both.
  setMode(mode: SurfaceMode) {
    this.mode = mode;
    if (this.surface) this.surface.material = this.material();
    if (this.frame) this.setFrame(this.frame, this.markers);
    this.render();
  }

  // The surface's material: the FTLE colours while the overlay is on, else the mode's.
  private material(): THREE.Material {
    return this.ftleOn ? this.ftleMaterial : this.mode === "arrows" ? this.plain : this.texture.material;
  }

  // The FTLE overlay: r, g, b in [0, 1] per vertex (lcs.ts vertexColors), or undefined to
  // show the field again. Colours of another length than the mesh's are not shown.
  setFtle(colors: Float32Array | undefined) {
    const attr = this.surface?.geometry.getAttribute("ftle") as THREE.BufferAttribute | undefined;
    this.ftleOn = !!colors && !!attr && colors.length === attr.array.length;
    if (this.ftleOn) {
      (attr!.array as Float32Array).set(colors!);
      attr!.needsUpdate = true;
    }
    if (this.surface) this.surface.material = this.material();
    this.render();
  }

  // The dye: curves of [x, y, z] points on the mesh (each an unbroken run) drawn as thin
  // tubes through them, and the seeds as balls.
  setDye(curves: { points: number[][]; color: string }[], seeds: number[][], seedColor: string) {
    emptyGroup(this.dye, true);
    for (const c of curves) {
      if (c.points.length < 2) continue;
      const pts = c.points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
      const curve = new THREE.CatmullRomCurve3(pts, false, "centripetal");
      const segments = Math.min(4000, Math.max(8, 3 * pts.length));
      this.dye.add(new THREE.Mesh(new THREE.TubeGeometry(curve, segments, 0.006 * this.radius, 5, false), new THREE.MeshBasicMaterial({ color: c.color })));
    }
    for (const p of seeds) {
      const ball = new THREE.Mesh(new THREE.SphereGeometry(0.016 * this.radius, 12, 8), new THREE.MeshBasicMaterial({ color: seedColor }));
      ball.position.set(p[0], p[1], p[2]);
      this.dye.add(ball);
    }
    this.render();
  }

  // The periodic orbits of the shown frame (orbits.ts): closed tubes on the mesh, a little
  // thicker than the dye's.
  setOrbits(loops: { points: number[][]; color: string }[]) {
    emptyGroup(this.orbits, true);
    for (const loop of loops) {
      const pts = loop.points.slice(0, -1).map((p) => new THREE.Vector3(p[0], p[1], p[2]));
      if (pts.length < 3) continue;
      const curve = new THREE.CatmullRomCurve3(pts, true, "centripetal");
      const segments = Math.min(2000, Math.max(24, 3 * pts.length));
      this.orbits.add(new THREE.Mesh(new THREE.TubeGeometry(curve, segments, 0.008 * this.radius, 6, true), new THREE.MeshBasicMaterial({ color: loop.color })));
    }
    this.render();
  }

  // Places to point at (the key-frame report's first wrong frame of a surface guide, or the
  // two singularities whose paths could not be kept apart): a ring around each point in
  // the surface's tangent plane and a dot at it; undefined or [] for none.
  setMark(points: number[][] | undefined) {
    this.markAt = points ?? [];
    this.drawMark();
  }

  private drawMark() {
    emptyGroup(this.mark, true);
    for (const p of this.surface ? this.markAt : []) {
      const at = new THREE.Vector3(p[0], p[1], p[2]);
      // The ring is drawn over everything (the faces round a coarse mesh's point tilt away
      // from the vertex normal and would hide part of it; orbited away, it shows through
      // where the place is); the dot at the point itself is hidden by what is in front.
      const n = this.normalNear(at);
      const ringMaterial = new THREE.MeshBasicMaterial({ color: WRONG_PLACE_COLOR, depthTest: false });
      const ring = new THREE.Mesh(new THREE.TorusGeometry(0.06 * this.radius, 0.008 * this.radius, 8, 48), ringMaterial);
      ring.renderOrder = 3;
      ring.position.copy(at);
      ring.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
      const dot = new THREE.Mesh(new THREE.SphereGeometry(0.012 * this.radius, 10, 8), new THREE.MeshBasicMaterial({ color: WRONG_PLACE_COLOR }));
      dot.position.copy(at);
      this.mark.add(ring, dot);
    }
    this.render();
  }

  // The normal of the mesh's vertex nearest to p (the view's smooth normals).
  private normalNear(p: THREE.Vector3): THREE.Vector3 {
    const normals = this.surface?.geometry.getAttribute("normal");
    let best = -1;
    let bestD = Infinity;
    for (let v = 0; v < this.positions.length / 3; ++v) {
      const d = (this.positions[3 * v] - p.x) ** 2 + (this.positions[3 * v + 1] - p.y) ** 2 + (this.positions[3 * v + 2] - p.z) ** 2;
      if (d < bestD) (bestD = d), (best = v);
    }
    if (best < 0 || !normals) return new THREE.Vector3(0, 0, 1);
    const n = new THREE.Vector3(normals.getX(best), normals.getY(best), normals.getZ(best));
    return n.lengthSq() > 0 ? n.normalize() : new THREE.Vector3(0, 0, 1);
  }

  // Turns the camera about the mesh's centre (at the same distance) to look at p from
  // outside: along the direction from the centre to p, tilted towards the surface's normal
  // at p, so that a point on a concave or far side comes into view.
  face(p: number[]) {
    const at = new THREE.Vector3(p[0], p[1], p[2]);
    const center = this.controls.target;
    const out = at.clone().sub(center);
    const dir = (out.lengthSq() > 0 ? out.normalize() : new THREE.Vector3()).add(this.normalNear(at));
    if (dir.lengthSq() === 0) return;
    const distance = this.camera.position.distanceTo(center);
    this.camera.position.copy(center).addScaledVector(dir.normalize(), distance);
    this.controls.update();
    this.texture.invalidate();
    this.render();
  }

  // Whether the world point p (on the mesh) is seen by the camera: the first surface hit
  // on the ray from the camera to p is p itself (for tests).
  visible(p: number[]): boolean {
    if (!this.surface) return false;
    const q = new THREE.Vector3(p[0], p[1], p[2]);
    const from = this.camera.position.clone();
    const dir = q.clone().sub(from);
    const d = dir.length();
    const ray = new THREE.Raycaster(from, dir.normalize());
    const hit = ray.intersectObject(this.surface)[0];
    return !!hit && Math.abs(hit.distance - d) < 1e-3 * this.radius;
  }

  setFrame(frame: Frame, markers: number[][]) {
    this.frame = frame;
    this.markers = markers;
    this.texture.setField(frame.vectors);
    for (const c of [...this.overlay.children]) {
      this.overlay.remove(c);
      (c as THREE.Mesh).geometry?.dispose();
    }
    const n = this.positions.length / 3;
    const step = Math.max(1, Math.floor(n / 1500));
    // Directions only (a designed field's speed falls off far from its elements): every
    // arrow has the same length, with a head (two short strokes back from the tip, in the
    // plane of the arrow and the normal's cross product); exact zeros get none.
    const len = 0.045 * this.radius;
    const seg: number[] = [];
    const normals = this.surface?.geometry.getAttribute("normal");
    for (let v = 0; this.mode !== "texture" && v < n; v += step) {
      const p = [this.positions[3 * v], this.positions[3 * v + 1], this.positions[3 * v + 2]];
      const d = [frame.vectors[3 * v], frame.vectors[3 * v + 1], frame.vectors[3 * v + 2]];
      const m = Math.hypot(d[0], d[1], d[2]);
      if (!(m > 0)) continue;
      const u = d.map((x) => x / m);
      const tip = p.map((x, k) => x + len * u[k]);
      seg.push(...p, ...tip);
      if (normals) {
        const nv = [normals.getX(v), normals.getY(v), normals.getZ(v)];
        const side = [nv[1] * u[2] - nv[2] * u[1], nv[2] * u[0] - nv[0] * u[2], nv[0] * u[1] - nv[1] * u[0]];
        for (const sgn of [1, -1]) seg.push(...tip, ...tip.map((x, k) => x - 0.35 * len * u[k] + sgn * 0.2 * len * side[k]));
      }
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(seg, 3));
    this.overlay.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: this.mode === "both" ? 0xf97316 : 0x334155 })));
    for (const s of frame.singularities) {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.025 * this.radius, 12, 8), new THREE.MeshBasicMaterial({ color: typeColor(s.type) }));
      m.position.set(s.position[0], s.position[1], s.position[2] ?? 0);
      this.overlay.add(m);
    }
    for (const p of markers) {
      const m = new THREE.Mesh(new THREE.BoxGeometry(0.04 * this.radius, 0.04 * this.radius, 0.04 * this.radius), new THREE.MeshBasicMaterial({ color: 0x111827, wireframe: true }));
      m.position.set(p[0], p[1], p[2] ?? 0);
      this.overlay.add(m);
    }
    this.render();
  }

  // The analysis's singularity paths coloured by time over `range` (surface/paths.ts);
  // undefined hides them.
  setPaths(analysis: Analysis | undefined, range: [number, number], selected = -1) {
    emptyGroup(this.paths, false);
    if (analysis) for (const o of pathObjects(analysis, range, this.radius, selected)) this.paths.add(o);
    this.render();
  }

  // Steps the moving texture by n and draws at once (the page's ticker calls it).
  animate(n = 1) {
    if (!this.surface || this.mode === "arrows" || this.ftleOn) return;
    this.texture.step(this.camera, n);
    this.renderer.render(this.scene, this.camera);
  }

  private pick(e: PointerEvent) {
    const p = this.hit(e);
    if (p) this.onPick([p.x, p.y, p.z]);
  }

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
