// The surface designer's view: the mesh, the current frame's field as short arrows at a
// subset of vertices, singularities coloured by type, and design elements. A click on the
// surface reports the picked point [x, y, z] (the server snaps positions to the surface).
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { Frame, MeshData } from "./api";
import { typeColor } from "./colors";

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
  onPick: (p: number[]) => void = () => {};

  constructor(host: HTMLElement) {
    const w = host.clientWidth || 512;
    const h = host.clientHeight || 512;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setSize(w, h);
    this.renderer.setClearColor(0xffffff);
    host.appendChild(this.renderer.domElement);
    this.camera = new THREE.PerspectiveCamera(40, w / h, 0.001, 1000);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.render());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 3.0));
    this.scene.add(this.overlay);
    const el = this.renderer.domElement;
    // A click (not a drag of the camera) picks a point.
    el.addEventListener("pointerdown", (e) => (this.down = [e.clientX, e.clientY]));
    el.addEventListener("pointerup", (e) => {
      if (this.down && Math.hypot(e.clientX - this.down[0], e.clientY - this.down[1]) < 4) this.pick(e);
      this.down = undefined;
    });
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
    this.surface = new THREE.Mesh(g, new THREE.MeshStandardMaterial({ color: 0xe8edf3, roughness: 0.9, side: THREE.DoubleSide }));
    this.scene.add(this.surface);
    const s = g.boundingSphere!;
    this.radius = s.radius;
    this.controls.target.copy(s.center);
    this.camera.position.copy(s.center).add(new THREE.Vector3(0.2, -1, 0.6).normalize().multiplyScalar(3 * s.radius));
    this.controls.update();
    this.render();
  }

  setFrame(frame: Frame, markers: number[][]) {
    for (const c of [...this.overlay.children]) {
      this.overlay.remove(c);
      (c as THREE.Mesh).geometry?.dispose();
    }
    const n = this.positions.length / 3;
    const step = Math.max(1, Math.floor(n / 1500));
    // Directions only (a designed field's speed falls off far from its elements): every
    // arrow has the same length; exact zeros get none.
    const len = 0.045 * this.radius;
    const seg: number[] = [];
    for (let v = 0; v < n; v += step) {
      const p = [this.positions[3 * v], this.positions[3 * v + 1], this.positions[3 * v + 2]];
      const d = [frame.vectors[3 * v], frame.vectors[3 * v + 1], frame.vectors[3 * v + 2]];
      const m = Math.hypot(d[0], d[1], d[2]);
      if (!(m > 0)) continue;
      seg.push(...p, p[0] + (len * d[0]) / m, p[1] + (len * d[1]) / m, p[2] + (len * d[2]) / m);
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(seg, 3));
    this.overlay.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: 0x334155 })));
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

  private pick(e: PointerEvent) {
    if (!this.surface) return;
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const hit = ray.intersectObject(this.surface)[0];
    if (hit) this.onPick([hit.point.x, hit.point.y, hit.point.z]);
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
