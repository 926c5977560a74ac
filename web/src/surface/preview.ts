// The surface's moving preview: texture advection in image space (van Wijk 2003,
// "IBFV-S"). A velocity pass draws the mesh into an off-screen target, each pixel holding
// the direction in which the field at that point of the surface moves on the screen (the
// vertex's unit field vector, projected by the camera); it is read back when the camera,
// the field or the size changes. The picture (preview/advect.ts) is carried along those
// directions each step, drawn out along them by a short LIC, and shown on the surface by a material that looks it up at the
// fragment's screen position, shaded by the surface's normal. Texture advection on the
// CPU at half the canvas's resolution (280² for the page's 560² view). When the camera
// moves, the picture is carried with the surface (surface/reproject.ts), so that an orbit
// turns the texture with the mesh instead of sliding the mesh under it.
import * as THREE from "three";
import { Advection, type PixelFlow } from "../preview/advect";
import { decodeOld, reproject, reprojectFragment, reprojectVertex, valuesLike } from "./reproject";

const velocityVertex = /* glsl */ `
attribute vec3 direction;
uniform float eps;
uniform vec2 resolution;
varying vec2 vDir;
void main() {
  vec4 c0 = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
  vec4 c1 = projectionMatrix * modelViewMatrix * vec4(position + eps * direction, 1.0);
  vec2 d = (c1.xy / c1.w - c0.xy / c0.w) * resolution;
  float n = length(d);
  vDir = n > 1e-9 ? d / n : vec2(0.0);
  gl_Position = c0;
}`;
const velocityFragment = /* glsl */ `
varying vec2 vDir;
void main() {
  gl_FragColor = vec4(0.5 + 0.5 * clamp(vDir, -1.0, 1.0), 1.0, 1.0);
}`;
const showVertex = /* glsl */ `
varying vec3 vNormal;
void main() {
  vNormal = normalize(normalMatrix * normal);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
const showFragment = /* glsl */ `
uniform sampler2D picture;
uniform vec2 size;
varying vec3 vNormal;
void main() {
  vec2 uv = vec2(gl_FragCoord.x / size.x, 1.0 - gl_FragCoord.y / size.y);
  float g = texture2D(picture, uv).r;
  float light = 0.6 + 0.4 * abs(normalize(vNormal).z);
  gl_FragColor = vec4(vec3(0.12 + 0.85 * g) * light, 1.0);
}`;

export class SurfaceTexture {
  readonly material: THREE.ShaderMaterial;
  private readonly velocityMaterial: THREE.ShaderMaterial;
  private readonly velocityScene = new THREE.Scene();
  private velocityMesh: THREE.Mesh | undefined;
  private readonly reprojectMaterial: THREE.ShaderMaterial;
  // The camera's projection × view matrix when the flow was last read (undefined: none).
  private seen: THREE.Matrix4 | undefined;
  private seed = 0x9e3779b9;
  private target: THREE.WebGLRenderTarget | undefined;
  private texture: THREE.DataTexture | undefined;
  private advection: Advection | undefined;
  private flow: PixelFlow | undefined;
  private pixels = new Uint8Array();
  private grey = new Uint8Array();
  private dirty = true;
  width = 0;
  height = 0;

  constructor(
    private readonly renderer: THREE.WebGLRenderer,
    private readonly stepPixels = 1.5,
  ) {
    this.velocityMaterial = new THREE.ShaderMaterial({
      vertexShader: velocityVertex,
      fragmentShader: velocityFragment,
      uniforms: { eps: { value: 1e-3 }, resolution: { value: new THREE.Vector2(1, 1) } },
      side: THREE.DoubleSide,
    });
    this.reprojectMaterial = new THREE.ShaderMaterial({
      vertexShader: reprojectVertex,
      fragmentShader: reprojectFragment,
      uniforms: { previous: { value: new THREE.Matrix4() }, resolution: { value: new THREE.Vector2(1, 1) } },
      side: THREE.DoubleSide,
    });
    this.material = new THREE.ShaderMaterial({
      vertexShader: showVertex,
      fragmentShader: showFragment,
      uniforms: { picture: { value: null }, size: { value: new THREE.Vector2(1, 1) } },
      side: THREE.DoubleSide,
    });
  }

  // The mesh's geometry (shared with the view's surface); `radius` its bounding radius.
  setGeometry(geometry: THREE.BufferGeometry, radius: number) {
    if (this.velocityMesh) this.velocityScene.remove(this.velocityMesh);
    const n = geometry.getAttribute("position").count;
    geometry.setAttribute("direction", new THREE.BufferAttribute(new Float32Array(3 * n), 3));
    this.velocityMesh = new THREE.Mesh(geometry, this.velocityMaterial);
    this.velocityScene.add(this.velocityMesh);
    this.velocityMaterial.uniforms.eps.value = 1e-3 * radius;
    this.dirty = true;
  }

  // The frame's world vectors per vertex (3 numbers each): their directions.
  setField(vectors: ArrayLike<number>) {
    const attr = this.velocityMesh?.geometry.getAttribute("direction") as THREE.BufferAttribute | undefined;
    if (!attr) return;
    const a = attr.array as Float32Array;
    for (let v = 0; 3 * v < a.length; ++v) {
      const x = vectors[3 * v] ?? 0;
      const y = vectors[3 * v + 1] ?? 0;
      const z = vectors[3 * v + 2] ?? 0;
      const m = Math.hypot(x, y, z);
      a[3 * v] = m > 0 ? x / m : 0;
      a[3 * v + 1] = m > 0 ? y / m : 0;
      a[3 * v + 2] = m > 0 ? z / m : 0;
    }
    attr.needsUpdate = true;
    this.dirty = true;
  }

  // The camera moved (or the canvas changed size): the flow is read again.
  invalidate() {
    this.dirty = true;
  }

  get ready(): boolean {
    return this.flow !== undefined;
  }

  // `n` steps along the field as the camera sees it.
  step(camera: THREE.Camera, n = 1) {
    if (!this.velocityMesh) return;
    if (this.dirty) this.readFlow(camera);
    if (!this.advection || !this.flow || !this.texture) return;
    for (let k = 0; k < n; ++k) this.advection.step(this.flow);
    this.advection.shown(this.flow, 5, this.grey);
    const data = this.texture.image.data as Uint8Array;
    for (let k = 0; k < this.grey.length; ++k) {
      const g = this.grey[k];
      data[4 * k] = g;
      data[4 * k + 1] = g;
      data[4 * k + 2] = g;
      data[4 * k + 3] = 255;
    }
    this.texture.needsUpdate = true;
  }

  private resize() {
    const buffer = this.renderer.getDrawingBufferSize(new THREE.Vector2());
    const w = Math.max(16, Math.round(buffer.x / 2));
    const h = Math.max(16, Math.round(buffer.y / 2));
    this.material.uniforms.size.value.set(buffer.x, buffer.y);
    if (w === this.width && h === this.height) return;
    this.width = w;
    this.height = h;
    this.target?.dispose();
    this.target = new THREE.WebGLRenderTarget(w, h, { depthBuffer: true });
    this.texture?.dispose();
    this.texture = new THREE.DataTexture(new Uint8Array(4 * w * h), w, h, THREE.RGBAFormat, THREE.UnsignedByteType);
    this.texture.magFilter = THREE.LinearFilter;
    this.texture.minFilter = THREE.LinearFilter;
    this.material.uniforms.picture.value = this.texture;
    this.advection = new Advection(w, h, { seed: 11 });
    this.pixels = new Uint8Array(4 * w * h);
    this.grey = new Uint8Array(w * h);
    this.flow = undefined;
    this.seen = undefined;
  }

  // A random number in [0, 1) (xorshift32): which pixel's value a pixel new in view takes.
  private fresh(): number {
    let s = this.seed;
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    this.seed = s >>> 0;
    return this.seed / 4294967296;
  }

  // Draws the mesh into the target with `material` and reads the bytes back.
  private pass(camera: THREE.Camera, material: THREE.ShaderMaterial, clear: THREE.Color, clearAlpha: number) {
    const before = this.renderer.getRenderTarget();
    const color = this.renderer.getClearColor(new THREE.Color());
    const alpha = this.renderer.getClearAlpha();
    this.velocityMesh!.material = material;
    this.renderer.setRenderTarget(this.target!);
    this.renderer.setClearColor(clear, clearAlpha);
    this.renderer.clear();
    this.renderer.render(this.velocityScene, camera);
    this.renderer.readRenderTargetPixels(this.target!, 0, 0, this.width, this.height, this.pixels);
    this.renderer.setRenderTarget(before);
    this.renderer.setClearColor(color, alpha);
    this.velocityMesh!.material = this.velocityMaterial;
  }

  // The camera moved since the flow was last read: each pixel of the picture takes the
  // value its surface point had under the old camera.
  private follow(camera: THREE.Camera, now: THREE.Matrix4) {
    if (!this.seen || !this.advection || !this.flow || this.seen.equals(now)) return;
    const { width: w, height: h } = this;
    this.reprojectMaterial.uniforms.previous.value.copy(this.seen);
    this.reprojectMaterial.uniforms.resolution.value.set(w, h);
    this.pass(camera, this.reprojectMaterial, new THREE.Color(1, 1, 1), 1);
    const from = decodeOld(this.pixels, w, h);
    const out = new Float32Array(w * h);
    const image = this.advection.image;
    reproject(image, this.flow.mask, w, h, from, valuesLike(image, this.flow.mask, () => this.fresh()), out);
    this.advection.image = out;
  }

  private readFlow(camera: THREE.Camera) {
    this.resize();
    const { width: w, height: h } = this;
    camera.updateMatrixWorld();
    const now = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    this.follow(camera, now);
    this.seen = now;
    this.velocityMaterial.uniforms.resolution.value.set(w / 2, h / 2); // NDC → pixels
    this.pass(camera, this.velocityMaterial, new THREE.Color(0.5, 0.5, 0), 0);
    // Read back bottom row first; the flow is top row first, y down.
    const flow: PixelFlow = { width: w, height: h, dx: new Float32Array(w * h), dy: new Float32Array(w * h), mask: new Uint8Array(w * h) };
    const s = this.stepPixels;
    for (let j = 0; j < h; ++j)
      for (let i = 0; i < w; ++i) {
        const src = 4 * ((h - 1 - j) * w + i);
        const k = j * w + i;
        if (this.pixels[src + 2] < 128) continue;
        flow.mask[k] = 1;
        flow.dx[k] = s * ((2 * this.pixels[src]) / 255 - 1);
        flow.dy[k] = -s * ((2 * this.pixels[src + 1]) / 255 - 1);
      }
    this.flow = flow;
    this.dirty = false;
  }
}
