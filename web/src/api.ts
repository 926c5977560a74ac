// The JSON API of `tvf serve` (docs/serve_api.md). Every call returns the parsed body or
// throws ApiError with the server's one-sentence message.
import type { Keyframe, Scene } from "./scene";

// `place`: where the error is, when the server knows (docs/serve_api.md): the file, the
// JSON path of the value ("elements[2].type"), its line and column in the request body.
export interface ErrorPlace {
  file?: string;
  json_path?: string;
  line?: number;
  column?: number;
}

export class ApiError extends Error {
  constructor(
    readonly status: number,
    message: string,
    readonly place: ErrorPlace = {},
  ) {
    super(message);
  }
}

// `revision`: the scene revision a change was made on, sent as If-Match (the server
// answers 412 when the scene has moved on since: another tab or client changed it).
// `timeout`: seconds after which the request is given up (ApiError 0), for the reads the
// page's status handling waits on: a connection that never answers (a lost packet, a
// stalled proxy) must not freeze the page, which then asks again. Renders and uploads,
// which may take minutes, have none.
async function call<T>(method: string, path: string, body?: unknown, revision?: number, timeout?: number): Promise<T> {
  const init: RequestInit = { method };
  if (timeout !== undefined) init.signal = AbortSignal.timeout(timeout * 1000);
  const headers: Record<string, string> = {};
  if (body !== undefined) init.body = JSON.stringify(body);
  if (method !== "GET") headers["Content-Type"] = "application/json";
  if (revision !== undefined) headers["If-Match"] = `"${revision}"`;
  init.headers = headers;
  let res: Response;
  let text: string;
  try {
    res = await fetch(path, init);
    text = await res.text();
  } catch (e) {
    if (e instanceof DOMException && e.name === "TimeoutError")
      throw new ApiError(0, `${method} ${path}: no answer within ${timeout} s`);
    throw e;
  }
  let json: unknown;
  try {
    json = JSON.parse(text);
  } catch {
    throw new ApiError(res.status, `${method} ${path}: the server answered ${res.status} without JSON`);
  }
  if (!res.ok) {
    const { error, file, json_path, line, column } = json as { error?: string } & ErrorPlace;
    throw new ApiError(res.status, error ?? `HTTP ${res.status}`, { file, json_path, line, column });
  }
  return json as T;
}

// A frame in binary (GET /api/frame/J?format=f32, docs/serve_api.md "Binary frames"): a
// 4-byte little-endian length n, n bytes of JSON (the frame without "vectors", with
// "count"), then `count` little-endian float32 values. A quarter of the JSON's bytes,
// and the vectors need no parsing. Errors are JSON, as for every call.
export function parseBinaryFrame(bytes: ArrayBuffer): Frame {
  const view = new DataView(bytes);
  const n = view.getUint32(0, true);
  const head = JSON.parse(new TextDecoder().decode(new Uint8Array(bytes, 4, n))) as Omit<Frame, "vectors"> & { count: number };
  const start = 4 + n;
  if (start % 4 !== 0 || start + 4 * head.count > bytes.byteLength) throw new Error("a binary frame of the wrong length");
  // Little-endian floats read in place on little-endian machines (every browser's), else one by one.
  const little = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;
  let vectors: Float32Array;
  if (little) vectors = new Float32Array(bytes, start, head.count);
  else {
    vectors = new Float32Array(head.count);
    for (let k = 0; k < head.count; ++k) vectors[k] = view.getFloat32(start + 4 * k, true);
  }
  const frame = head as unknown as Frame & { count?: number };
  delete frame.count;
  frame.vectors = vectors;
  return frame;
}

// A binary frame, given up after `timeout` seconds (ApiError 0) as call's reads.
async function frameCall(path: string, timeout: number): Promise<Frame> {
  let res: Response;
  let bytes: ArrayBuffer;
  try {
    res = await fetch(path, { signal: AbortSignal.timeout(timeout * 1000) });
    bytes = await res.arrayBuffer();
  } catch (e) {
    if (e instanceof DOMException && e.name === "TimeoutError") throw new ApiError(0, `GET ${path}: no answer within ${timeout} s`);
    throw e;
  }
  if (res.ok) return parseBinaryFrame(bytes);
  const text = new TextDecoder().decode(bytes);
  let error: string | undefined;
  try {
    error = (JSON.parse(text) as { error?: string }).error;
  } catch {
    throw new ApiError(res.status, `GET ${path}: the server answered ${res.status} without JSON`);
  }
  throw new ApiError(res.status, error ?? `HTTP ${res.status}`);
}

export interface SceneState {
  revision: number;
  scene: Scene;
  text?: string; // the scene as the file holds it (keys in the order of DESIGN §10)
  path: string;
  can_undo: boolean;
  can_redo: boolean;
}
export interface Status {
  revision: number;
  result_revision: number;
  state: "running" | "ready" | "failed";
  progress: [number, number];
  // While a solve runs a step no frame count measures (the key-frame topology plan).
  stage?: string;
  error: string;
  warnings?: string[];
  method?: string;
  // With solver.keyframe_topology "matched": per interval between consecutive key frames,
  // whether its frames are the guide field (no bifurcation but the planned ones) or left
  // free, and why.
  keyframe_intervals?: {
    keyframes: [number, number];
    guided: boolean;
    fallback: boolean;
    routing: string;
    matched: number;
    linked: number;
    created: number;
    cancelled: number;
    turning?: number; // nodes the guide leaves turning a whole turn
    unguided_reason?: string;
    // Turned down by the surface guide's check: where its first wrong frame goes wrong.
    first_wrong?: {
      t: number;
      found: number;
      planned: number;
      extra: boolean;
      type: string;
      at: [number, number, number];
      distance?: number;
      nearest_type?: string;
      face_edges: number;
    };
    // The default separation lowered where it could not be kept: from what, to what.
    lowered_from?: number;
    separation?: number;
    // Two paths that could not be kept apart: at t the two (`types`; the second a pair's
    // saddle–node template when `template`) at `points`, `distance` apart of `required`.
    collision_at?: {
      t: number;
      points: [number[], number[]];
      types: [string, string];
      template: boolean;
      distance: number;
      required: number;
    };
    // Where the guide leaves a node turning: the key frame that would hold it (its
    // elements where the plan carries them half-way; from/to: each one's element in the
    // key frames before and after).
    middle_keyframe?: { keyframe: Keyframe; from: number[]; to: number[] };
  }[];
  seconds?: number;
  // The result's domain id (changes when the mesh does: GET /api/mesh again), its
  // analysis state, and the revision of the last analysis made (issue 15: the field is
  // published first, its analysis follows).
  domain?: number;
  analysis?: "running" | "ready" | "failed";
  analysis_error?: string;
  analysis_revision?: number;
  // The shown frame of a solve under way, ready before its other frames (GET /api/preview).
  preview_revision?: number;
  preview_frame?: number;
  sequence?: number; // orders the statuses of one server session (pushed and polled alike)
  session?: string; // the server's session: another one after a restart
}
export interface FrameSingularity {
  position: number[];
  type: string;
  index: number;
  path: number;
}
export interface Frame {
  revision: number;
  frame: number;
  frames: number;
  t: number;
  vectors: ArrayLike<number>; // world x, y, z per vertex (a Float32Array from the binary frame)
  singularities: FrameSingularity[];
  preview?: boolean; // GET /api/preview: one frame of a solve under way
}
export interface MeshData {
  revision: number;
  domain?: number;
  planar: boolean;
  grid?: { size: [number, number]; min: [number, number]; max: [number, number] };
  vertices: number[];
  faces: number[];
}
export interface Analysis {
  revision: number;
  frames: number;
  times: number[];
  paths: { id: number; type: string; birth: number; death: number; points: number[][] }[];
  // kind "creation" | "cancellation", then the Hopf events (kind "hopf", DESIGN §12)
  bifurcations: { t: number; position: number[]; kind: string; paths: number[]; criticality?: string }[];
  coherence: number[];
  // Closed streamlines per frame (DESIGN §12); absent from servers older than them.
  periodic_orbits?: { frame: number; t: number; center: number[]; radius: number; stability: string; points: number[][]; id: number }[];
}

// The longest a read may take: the server itself waits up to 20 s for a field or an
// analysis being made (field_wait_seconds), then answers 409.
const READ_TIMEOUT = 60;

export const api = {
  scene: () => call<SceneState>("GET", "api/scene", undefined, undefined, READ_TIMEOUT),
  putScene: (scene: Scene, revision?: number) => call<SceneState>("PUT", "api/scene", scene, revision),
  edit: (edit: unknown, revision?: number) => call<{ revision: number; summary: string }>("POST", "api/edit", edit, revision),
  undo: (revision?: number) => call<SceneState>("POST", "api/undo", undefined, revision),
  redo: (revision?: number) => call<SceneState>("POST", "api/redo", undefined, revision),
  status: () => call<Status>("GET", "api/status", undefined, undefined, READ_TIMEOUT),
  mesh: () => call<MeshData>("GET", "api/mesh", undefined, undefined, READ_TIMEOUT),
  frame: (j: number) => frameCall(`api/frame/${j}?format=f32`, READ_TIMEOUT),
  analysis: () => call<Analysis>("GET", "api/analysis", undefined, undefined, READ_TIMEOUT),
  preview: () => frameCall("api/preview?format=f32", READ_TIMEOUT),
  // The deformation key's translate that moves a streamline's seed to `to` (on surfaces in
  // the log-map chart around the seed, computed by the library).
  seedTranslation: (seed: number[], to: number[]) => call<{ translate: number[] }>("POST", "api/seed_translation", { seed, to }),
  // The coordinates [u, v] of `to` in the chart an element at `at` is designed in (on
  // surfaces the log map around `at`, in the frame of its face): a bifurcation's axis.
  chartCoordinates: (at: number[], to: number[]) => call<{ coords: number[] }>("POST", "api/chart_coordinates", { at, to }),
  exportField: (format: string, dir: string) => call<{ revision: number; files: string[] }>("POST", "api/export", { format, dir }),
  // On surfaces `camera` is the view to render from (SurfaceView.cameraView()).
  render: (name: string, size: number, camera?: { view: number[]; up: number[]; fov: number }, frames?: number) =>
    call<{ revision: number; file: string; frames: number; seconds: number }>("POST", "api/render", { name, size, ...(camera ?? {}), ...(frames ? { frames } : {}) }),
  async upload(file: File): Promise<{ file: string }> {
    const res = await fetch(`api/upload?name=${encodeURIComponent(file.name)}`, {
      method: "POST",
      headers: { "Content-Type": "application/octet-stream" },
      body: await file.arrayBuffer(),
    });
    const json = await res.json();
    if (!res.ok) throw new ApiError(res.status, json.error ?? `HTTP ${res.status}`);
    return json;
  },
};
