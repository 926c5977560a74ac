// The space-time view (paper Fig. 2): the domain's rectangle stretched along a time axis,
// singularity paths as curves coloured by type, bifurcations as spheres, and the current
// time as a plane. A click on a bifurcation picks it (for removal or moving).
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import type { Analysis } from "./api";
import { BIFURCATION_COLOR, typeColor } from "./colors";

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
  onPick: (index: number) => void = () => {};

  constructor(host: HTMLElement) {
    const w = host.clientWidth || 360;
    const h = host.clientHeight || 300;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setSize(w, h);
    this.renderer.setClearColor(0xffffff);
    host.appendChild(this.renderer.domElement);
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

  set(analysis: Analysis, min: [number, number], max: [number, number], range: [number, number]) {
    this.min = min;
    this.max = max;
    this.range = range;
    for (const child of [...this.content.children]) {
      this.content.remove(child);
      const m = child as THREE.Mesh;
      m.geometry?.dispose();
      (m.material as THREE.Material | undefined)?.dispose?.();
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
    for (const path of analysis.paths) {
      const pts = path.points.map((p) => this.map(p[0], p[1], p[3]));
      if (pts.length < 2) continue;
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: typeColor(path.type) }));
      this.content.add(line);
    }
    this.bifurcationMeshes = analysis.bifurcations.map((b, i) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.05, 16, 12), new THREE.MeshBasicMaterial({ color: BIFURCATION_COLOR }));
      m.position.copy(this.map(b.position[0], b.position[1], b.t));
      m.userData.index = i;
      this.content.add(m);
      return m;
    });
    this.highlight(this.selected);
  }

  setTime(t: number) {
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
