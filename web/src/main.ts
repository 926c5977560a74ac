// The tvf designer: the page that `tvf serve` serves. Every change is a new scene (or an
// edit entry) sent to the server, which validates it, saves it, and re-solves in the
// background; the server pushes its status (server-sent events; the page polls where the
// stream is unavailable) and the page shows the newest finished field. Changes go
// one at a time, each naming the revision it was made on (changes.ts): a quick burst of
// clicks builds on itself, and a change refused because another tab changed the scene is
// applied again on top of that change (or, when it cannot be, reported).
import "./style.css";
import { api, ApiError, type Analysis, type Frame, type MeshData, type SceneState, type Status } from "./api";
import { locateJsonPath } from "./error_place";
import { ChangeQueue } from "./changes";
import { BIFURCATION_COLOR, PATHLINE_COLOR, STREAKLINE_COLOR, STREAMLINE_COLOR, typeColor, WRONG_PLACE_COLOR } from "./colors";
import { CoherencePlot } from "./coherence";
import type { GridField } from "./lic";
import { ringMotion } from "./preview/advect";
import { drawArrows, PlanarPreview } from "./preview/planar";
import { Ticker } from "./preview/ticker";
import * as S from "./scene";
import { SpaceTimeView } from "./spacetime";
import { spaceTimePathline } from "./spacetime_draw";
import { SurfaceView, type SurfaceMode } from "./surface";
import { bifurcationAt, boundingRadius, surfaceHandleAt as handleOnSurface } from "./surface/handles";
import { TimeStrip } from "./surface/timestrip";
import { resample } from "./stroke";
import { rounded, View } from "./view";
import { DYE_COLOR, drawLegend, LcsOverlay, unresolvedNotes, vertexColors } from "./lcs";
import { orbitsAt } from "./orbits";

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;

// Where a change's time goes (window.tvf.marks; the latency test reads it): the last 64
// steps as [what, performance.now()].
const marks: [string, number][] = [];
function mark(what: string) {
  marks.push([what, performance.now()]);
  if (marks.length > 64) marks.shift();
}

const canvas = $<HTMLCanvasElement>("field");
const ctx = canvas.getContext("2d")!;
const slider = $<HTMLInputElement>("time");
const message = $<HTMLPreElement>("message");
const sceneText = $<HTMLTextAreaElement>("scene-json");

// The moving previews (preview/, surface/preview.ts), stepped about 30 times a second,
// except while a change of this page waits for its picture: the server solving it shares
// the machine's cores with the page, and a step of the texture costs a core 5–30 ms (in a
// browser without a GPU, most of one core at 30 steps a second; issue 15).
const planarPreview = new PlanarPreview(256);
const ticker = new Ticker((n) => {
  if (!state.scene || waitingForPicture()) return;
  if (planar()) {
    if (state.mesh?.grid && shownFrame()) {
      planarPreview.step(n);
      redraw();
    }
  } else surface?.animate(n);
});

interface State {
  scene?: SceneState;
  mesh?: MeshData;
  meshDomain?: number; // the server's id of the mesh's domain (status.domain)
  resultRevision: number;
  analysis?: Analysis; // of analysisRevision: it follows the field, so it can be older
  analysisRevision: number;
  // The current frame of a solve under way, shown before its result is complete (the
  // per-frame generators make the shown frame first: GET /api/preview).
  preview?: Frame;
  shownRevision: number; // the revision of the field drawn now
  frames: Map<number, Frame>;
  frame: number;
  tool: string;
  selected?: S.Handle;
  selectedBifurcation: number;
  drag?: { handle: S.Handle; scene: S.Scene };
  stroke?: S.Vec[];
  cancelPicks: number[][];
  linkFrom?: S.Handle; // Link tool: the key-frame element picked first
  // The places marked on the surface by an interval's "show where" (the surface guide's
  // first wrong frame, status keyframe_intervals[interval].first_wrong, or the two paths
  // that could not be kept apart, .collision_at) of that result.
  wrongPlace?: { revision: number; interval: number; at: number[][] };
  playing: boolean;
  jsonDirty: boolean;
}
const state: State = {
  resultRevision: -1,
  analysisRevision: -1,
  shownRevision: -1,
  frames: new Map(),
  frame: 0,
  tool: "select",
  selectedBifurcation: -1,
  cancelPicks: [],
  playing: false,
  jsonDirty: false,
};

const spacetime = new SpaceTimeView($("spacetime"));
const coherence = new CoherencePlot($("coherence"));
const strip = new TimeStrip($<HTMLCanvasElement>("timestrip"));
let surface: SurfaceView | undefined;
// FTLE and dye over the planar view or on the surface (lcs.ts).
const lcs = new LcsOverlay(
  () => {
    redraw();
    showLcsOnSurface();
    showLcsNotes();
  },
  (m) => say(m, true),
  // A refusal that no longer stands (a good horizon after a bad one) leaves the status line,
  // if it is still what the line says.
  (m) => {
    if (message.textContent === m) say("");
  },
);
// Under the view: which dye lines and timelines the server could not resolve, and why
// (their chords are not the flow's curve there).
function showLcsNotes() {
  const box = $("lcs-notes");
  const notes = unresolvedNotes(lcs.dye, lcs.timelines);
  box.hidden = notes.length === 0;
  box.textContent = notes.map((n) => `note: ${n}`).join("\n");
}
function refreshLcs() {
  if (state.resultRevision < 0 || !state.mesh || !state.analysis) return;
  void lcs.update(currentTime(), state.analysis.times[0], state.mesh.grid);
}
// On a surface: the FTLE as the mesh's colours (values per vertex) with the legend in a
// small canvas over the view's corner, and the dye as curves on the mesh.
const surfaceLegend = $<HTMLCanvasElement>("surface-legend");
function showLcsOnSurface() {
  if (!surface || !state.mesh || state.mesh.planar) return;
  const a = lcs.ftle;
  const n = state.mesh.vertices.length / 3;
  const shown = a && a.values.length === n ? a : undefined;
  surface.setFtle(shown ? vertexColors(shown) : undefined);
  surfaceLegend.hidden = !shown;
  if (shown) {
    const g = surfaceLegend.getContext("2d")!;
    g.clearRect(0, 0, surfaceLegend.width, surfaceLegend.height);
    drawLegend(g, shown);
  }
  surface.setDye(lcs.curves(), lcs.seeds, DYE_COLOR);
}

function say(text: string, error = false) {
  message.textContent = text;
  message.classList.toggle("error", error);
}

function scene(): S.Scene {
  return state.scene!.scene;
}
function planar(): boolean {
  return !!state.scene && S.isPlanar(scene());
}
function currentTime(): number {
  return state.scene ? S.frameTime(scene(), state.frame) : 0;
}
function view(): View {
  const g = scene().domain.grid!;
  return new View(canvas.width, canvas.height, [g.min[0], g.min[1]], [g.max[0], g.max[1]]);
}

// ---- talking to the server ------------------------------------------------------------

function showScene(s: SceneState) {
  const framesChanged = !state.scene || state.scene.scene.time.frames !== s.scene.time.frames;
  state.scene = s;
  $("scene-path").textContent = s.path;
  if (!state.jsonDirty) sceneText.value = s.text ?? JSON.stringify(s.scene, null, 2);
  $<HTMLButtonElement>("undo").disabled = !s.can_undo;
  $<HTMLButtonElement>("redo").disabled = !s.can_redo;
  $<HTMLSelectElement>("generator").value = s.scene.generator;
  $<HTMLInputElement>("keep-topology").checked = S.keyframeTopologyMatched(s.scene);
  const d = s.scene.domain;
  $<HTMLSelectElement>("domain").value = d.grid ? "grid" : d.sphere ? "sphere" : d.torus ? "torus" : "mesh";
  if (framesChanged) {
    slider.max = String(s.scene.time.frames - 1);
    state.frame = Math.min(state.frame, s.scene.time.frames - 1);
    slider.value = String(state.frame);
    $<HTMLInputElement>("life-start").value = String(s.scene.time.range[0]);
    $<HTMLInputElement>("life-end").value = String(s.scene.time.range[1]);
  }
  const ticks = $("keyframe-ticks");
  ticks.innerHTML = "";
  for (const k of s.scene.keyframes ?? []) {
    const tick = document.createElement("span");
    const j = S.frameOf(s.scene, k.t);
    tick.style.left = `${(100 * j) / Math.max(1, s.scene.time.frames - 1)}%`;
    tick.title = `key frame t = ${k.t}`;
    ticks.appendChild(tick);
  }
  showDesignCurves();
  redraw();
}

// The design's pathlines in the space-time view, and on surfaces its pathlines and the
// streamlines of the key frame at the current frame.
function showDesignCurves() {
  const s = state.scene!.scene;
  const pathlines = (s.elements ?? []).flatMap((e) => (e.kind === "regular" ? [e.pathline] : []));
  if (S.isPlanar(s)) spacetime.setDesign(pathlines);
  if (!S.isPlanar(s) && surface) {
    const j = state.frame;
    const lines: { points: number[][]; color: string; dashed?: boolean; ends?: boolean }[] = pathlines.map((points) => ({ points, color: PATHLINE_COLOR }));
    // Singular elements' paths with their control points (the Select tool moves them).
    for (const e of s.elements ?? []) if (e.kind === "singular" && e.path.length > 1) lines.push({ points: e.path, color: "#0f172a", dashed: true });
    // Sketched streaklines: solid at their time t, dashed otherwise (as on the plane).
    const t = currentTime();
    for (const e of s.elements ?? []) if (e.kind === "streakline") lines.push({ points: e.points, color: STREAKLINE_COLOR, dashed: Math.abs(e.t - t) >= 0.02 });
    for (const k of s.keyframes ?? [])
      if (S.frameOf(s, k.t) === j) for (const sl of k.streamlines ?? []) lines.push({ points: sl.points, color: STREAMLINE_COLOR });
    // Links at this key frame (the Link tool): a thin tube to the partner's place, over the
    // surface (the chord would run inside it).
    for (const [here, there] of linksAtFrame(s, j)) lines.push({ points: overSurface(here, there), color: LINK_COLOR, ends: true });
    surface.setDesign(lines);
  }
}

const queue = new ChangeQueue({
  current: () => state.scene,
  put: async (s, revision) => {
    mark("put");
    const r = await api.putScene(s, revision);
    mark(`put answered ${r.revision}`);
    return r;
  },
  reload: () => api.scene(),
  show: showScene,
});

function otherClient(revision: number) {
  return `another tab or client changed the design (now revision ${revision})`;
}

// A change of the scene: `mutate` is applied to the newest scene when the change's turn
// comes. `rebase` false: a change that replaces the design (new, another domain, typed
// JSON) is not applied over another tab's change but reported.
async function change(mutate: (s: S.Scene) => S.Scene, what: string, rebase = true) {
  try {
    const r = await queue.change(mutate, rebase);
    if (!r.applied) say(`${otherClient(r.state.revision)}: the page shows it, and "${what}" was not applied; do it again if you still want it`, true);
    else if (r.rebased) say(`${what} (${otherClient(r.state.revision - 1)} meanwhile: applied on top of that change)`);
    else say(what);
  } catch (e) {
    say((e as Error).message, true);
    showErrorPlace(e);
    redraw();
  }
}

// Selects, in the scene's JSON, the value a refused change names (its JSON path).
function showErrorPlace(e: unknown) {
  const path = e instanceof ApiError ? e.place.json_path : undefined;
  if (!path) return;
  const range = locateJsonPath(sceneText.value, path);
  if (!range) return;
  sceneText.focus();
  sceneText.setSelectionRange(range.start, range.end);
  // The browser scrolls to the selection's end; a value over many lines (a sketch's points)
  // would show only its last line: scroll its first line into view, a third down.
  const line = sceneText.value.slice(0, range.start).split("\n").length - 1;
  const style = getComputedStyle(sceneText);
  const lineHeight = parseFloat(style.lineHeight) || 1.2 * parseFloat(style.fontSize) || 16;
  sceneText.scrollTop = Math.max(0, line * lineHeight - sceneText.clientHeight / 3);
}

// Export, render and edits use the field of the current revision: while it is being
// solved the server answers 409 after a while, and the page waits and asks again.
async function withField<T>(task: () => Promise<T>): Promise<T> {
  for (let k = 0; ; ++k) {
    try {
      return await task();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 409 && /still being generated/.test(e.message)) || k >= 60) throw e;
      say(`waiting for the field of revision ${state.scene?.revision}…`);
      await new Promise((r) => setTimeout(r, 1000));
    }
  }
}

// Runs a request that names the current revision after the queued changes; a 412 (the
// scene changed elsewhere) reloads the scene and says that `what` was not done.
async function onCurrentRevision<T>(what: string, task: (revision: number) => Promise<T>): Promise<T | undefined> {
  return queue.run(async () => {
    try {
      return await task(state.scene!.revision);
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 412)) throw e;
      const fresh = await api.scene();
      showScene(fresh);
      say(`${otherClient(fresh.revision)} before the ${what}: the ${what} was not applied; the page shows the new design`, true);
      return undefined;
    }
  });
}

async function edit(entry: unknown) {
  say("applying the edit…");
  try {
    const r = await onCurrentRevision("edit", async (revision) => {
      const done = await withField(() => api.edit(entry, revision));
      showScene(await api.scene());
      return done;
    });
    if (r) say(r.summary);
  } catch (e) {
    say((e as Error).message, true);
  }
}

// The server's status, as pushed by GET /api/events (or polled): shown one at a time, the
// newest waiting while one is being shown (loading a result takes a few requests).
async function showStatus(st: Status) {
  mark(`status ${st.revision} ${st.state} result ${st.result_revision} analysis ${st.analysis_revision}`);
  // The server started again (another session than the shown result's): its results
  // start over, and are shown even when their revision is not above the page's.
  const restarted = resultSession !== undefined && st.session !== resultSession;
  const label = $("status");
  label.dataset.state = st.state;
  lastState = st.state;
  lastStatus = st;
  if (st.state === "running")
    label.textContent = `rev ${st.revision} · ${st.stage ?? `solving ${st.progress[0]}/${st.progress[1]}`}…`;
  else if (st.state === "failed") label.textContent = `rev ${st.revision} · failed: ${st.error}`;
  else label.textContent = `rev ${st.revision} · ready in ${(st.seconds ?? 0).toFixed(2)} s`;
  if (st.state !== "running") {
    showKeyframeReport(st);
    showWarnings(st);
  }
  // Another tab or client changed the scene: show it (not while changes of ours are
  // under way or an element is dragged).
  if (state.scene && st.revision !== state.scene.revision && !queue.busy && !state.drag) {
    const fresh = await api.scene();
    if (!queue.busy && !state.drag && fresh.revision !== state.scene.revision) {
      showScene(fresh);
      say(`${otherClient(fresh.revision)}: the page shows it`);
    }
  }
  const preview = st.preview_revision ?? 0;
  if (preview > state.resultRevision && st.preview_frame === state.frame && preview !== state.preview?.revision) await loadPreview();
  // Results only move forward, unless the server started again (its first result is
  // loaded whatever its revision).
  if (st.result_revision > 0 && (st.result_revision > state.resultRevision || restarted)) await loadResult(st);
  // The current frame of the shown result, when its download failed (a 409 while the
  // server replaced its result, a busy server): asked for again.
  if (st.result_revision === state.resultRevision && state.resultRevision > 0 && !state.frames.has(state.frame))
    await showFrame(state.frame);
  // The analysis follows the field: loaded beside it, not waited for.
  const analysed = st.analysis_revision === undefined || st.analysis_revision === state.resultRevision;
  if (analysed && state.analysisRevision !== state.resultRevision && state.resultRevision > 0) void loadAnalysis(state.resultRevision);
  if (st.analysis === "failed" && st.result_revision === state.resultRevision) say(`the analysis failed: ${st.analysis_error ?? ""}`, true);
}

// Where an interval left free went wrong: the surface guide's first wrong frame (the extra
// or missing singularity), or the two singularities whose paths could not be kept apart
// (on the plane too), at the time they come closest.
function wrongPlaceOf(k: NonNullable<Status["keyframe_intervals"]>[number]) {
  if (k.guided) return undefined;
  const w = k.first_wrong;
  if (w)
    return { t: w.t, at: [w.at], title: `mark on the surface where the guide's ${w.extra ? "extra" : "missing"} ${w.type.replace(/_/g, " ")} lay` };
  const c = k.collision_at;
  if (c) {
    const other = c.template ? "the template of a pair" : `the ${c.types[1].replace(/_/g, " ")}`;
    return { t: c.t, at: c.points, title: `mark the ${c.types[0].replace(/_/g, " ")} and ${other} that come ${c.distance.toPrecision(2)} apart there (${c.required.toPrecision(2)} asked)` };
  }
  return undefined;
}

// Topology between key frames: one line per interval of the shown result. An interval left
// free by the surface guide's check or by two paths that could not be kept apart has
// "show where": it goes to that frame and marks the place (on a surface the camera turns
// to it): where a link, a key frame, a smaller region or separation would help; the mark
// stays until it is hidden or the result changes.
function showKeyframeReport(st: Status) {
  const box = $("keyframe-report");
  const intervals = st.state === "ready" ? (st.keyframe_intervals ?? []) : [];
  if (state.wrongPlace && (state.wrongPlace.revision !== st.result_revision || !intervals[state.wrongPlace.interval] || !wrongPlaceOf(intervals[state.wrongPlace.interval])))
    markWrongPlace(undefined);
  box.hidden = intervals.length === 0;
  box.classList.toggle("fallback", intervals.some((k) => k.fallback));
  box.replaceChildren(
    ...intervals.map((k, i) => {
      const line = document.createElement("div");
      line.className = "interval";
      const what = `key frames ${k.keyframes[0]} → ${k.keyframes[1]}: ${k.matched} carried${k.linked ? ` (${k.linked} linked)` : ""}, ${k.created} pairs created, ${k.cancelled} cancelled`;
      const turning = k.turning ? `; ${k.turning} node${k.turning > 1 ? "s" : ""} turning a whole turn (a key frame between the two can hold ${k.turning > 1 ? "them" : "it"})` : "";
      // Guided: the analysis should show the planned pairs' events and nothing else.
      const events = k.created + k.cancelled > 0 ? "no bifurcation but the pairs'" : "no bifurcation";
      const lowered = k.lowered_from && k.separation ? `, separation lowered to ${k.separation.toPrecision(3)} from the default ${k.lowered_from.toPrecision(3)}` : "";
      line.textContent = k.guided
        ? `${what}; guided (${k.routing} routing${lowered}): ${events}${turning}`
        : `${what}; not guided, left free (key frames only): ${k.unguided_reason ?? ""}`;
      const place = wrongPlaceOf(k);
      if (place && (planar() || surface)) {
        const shown = state.wrongPlace?.interval === i;
        const button = document.createElement("button");
        button.className = "show-wrong";
        button.textContent = shown ? "hide" : "show where";
        button.title = shown ? "Remove the mark" : `Go to t = ${place.t.toFixed(3)} and ${place.title}`;
        button.onclick = () => {
          if (shown) markWrongPlace(undefined);
          else {
            markWrongPlace({ revision: st.result_revision, interval: i, at: place.at });
            if (!planar()) surface?.face(place.at[0]);
            void showFrame(S.frameOf(scene(), place.t));
          }
          showKeyframeReport(st);
        };
        line.append(" ", button);
      }
      // A node left turning: the key frame the engine offers to hold it, one click away.
      const middle = k.middle_keyframe;
      if (middle) {
        const button = document.createElement("button");
        button.className = "add-middle-keyframe";
        button.textContent = "add this key frame";
        const held = (middle.keyframe.elements ?? []).map((e) => (e.type ? e.type.replace(/_/g, " ") : e.kind)).join(" and ");
        button.title = `Insert a key frame at t = ${middle.keyframe.t.toFixed(3)} holding the ${held} where the plan carries them then: it holds the node${(k.turning ?? 0) > 1 ? "s" : ""} left turning`;
        button.onclick = () =>
          void change(
            (s) => S.insertMiddleKeyframe(s, k.keyframes[0], middle.keyframe, middle.from, middle.to),
            `a key frame at t = ${middle.keyframe.t.toFixed(3)} added between keyframes[${k.keyframes[0]}] and keyframes[${k.keyframes[1]}], holding the ${held} where the plan carried them`,
            false, // made for these key frames: not applied on top of another client's change
          );
        line.append(" ", button);
      }
      return line;
    }),
  );
}

function markWrongPlace(place: State["wrongPlace"]) {
  state.wrongPlace = place;
  if (planar()) redraw();
  else surface?.setMark(place?.at);
}

// The generator's warnings on the shown result (paths that could not be kept apart, a node
// the guide leaves turning, a solve short of its tolerance), one per line.
function showWarnings(st: Status) {
  const box = $("warnings");
  const warnings = st.state === "ready" ? (st.warnings ?? []) : [];
  box.hidden = warnings.length === 0;
  box.textContent = warnings.map((w) => `warning: ${w}`).join("\n");
}

// A change of this page under way (its request not answered yet), or its revision being
// solved and not drawn yet.
function waitingForPicture(): boolean {
  if (queue.busy) return true;
  return lastState === "running" && !!state.scene && state.shownRevision < state.scene.revision;
}

let nextStatus: Status | null = null;
let showing = false;
let resultSession: string | undefined; // the server session of the shown result
let lastState: Status["state"] | "" = "";
let lastStatus: Status | null = null;
// Whether the page is behind the last status it saw (an event it could not follow up, a
// download that failed under load): then it asks for the status again, even when results
// are pushed, until it has caught up.
function behind(): boolean {
  const st = lastStatus;
  if (!st || st.state !== "ready" || st.result_revision <= 0) return false;
  if (state.resultRevision < st.result_revision || !state.frames.has(state.frame)) return true;
  // The shown result's analysis ready but not loaded (its download failed, say): asked again.
  return st.analysis !== "failed" && st.analysis_revision === state.resultRevision && state.analysisRevision !== state.resultRevision;
}
// Whether status `a` was made before `b` by the same server session. The page gets
// statuses from two sources, the event stream and polls; a poll's answer can arrive after
// newer pushed events (it was made before them, and waited for a core or a connection).
// Taken in the order they arrive, such an answer replaced the newer event waiting to be
// shown (the one saying the analysis was ready, say): the page then showed the older state
// and, told of nothing newer, waited for an analysis it already could have (issue 15,
// with the save overlapped). The server numbers its statuses (`sequence`): an older one is
// dropped; one of the same number is shown again (a solve's progress, or a retry).
function older(a: Status, b: Status): boolean {
  return a.session === b.session && a.sequence !== undefined && b.sequence !== undefined && a.sequence < b.sequence;
}
async function applyStatus(st: Status) {
  const newest = nextStatus ?? lastStatus;
  if (newest && older(st, newest)) {
    mark(`status ${st.sequence} dropped: older than ${newest.sequence}`);
    return;
  }
  nextStatus = st;
  if (showing) return;
  showing = true;
  try {
    while (nextStatus) {
      const s = nextStatus;
      nextStatus = null;
      await showStatus(s);
    }
  } catch (e) {
    mark(`status not shown: ${(e as Error).message}`);
    $("status").textContent = `server unreachable (${(e as Error).message})`;
  } finally {
    showing = false;
  }
}

// Results are pushed (server-sent events, GET /api/events): a change is shown as soon as
// its field is ready. Where the stream is unavailable (an old browser, the server's limit
// of streams, a proxy) the page polls /api/status instead, and retries the stream later.
let stream: EventSource | null = null;
function listen() {
  if (typeof EventSource === "undefined") return;
  const es = new EventSource("/api/events");
  es.addEventListener("status", (ev) => void applyStatus(JSON.parse((ev as MessageEvent<string>).data) as Status));
  es.onerror = () => {
    if (es.readyState === EventSource.CLOSED) {
      stream = null;
      setTimeout(listen, 10000);
    }
  };
  stream = es;
}
const streaming = () => stream !== null && stream.readyState === EventSource.OPEN;

// The fallback, and the solve's progress (not pushed: only its state is).
async function poll() {
  if (!streaming() || lastState === "running" || behind()) {
    try {
      await applyStatus(await api.status());
    } catch (e) {
      $("status").textContent = `server unreachable (${(e as Error).message})`;
    }
  }
  setTimeout(poll, streaming() ? 500 : state.playing ? 400 : 200);
}

// A new result: the current frame first (the picture), the mesh only when the domain
// changed; the analysis (paths, bifurcations, coherence) follows when the server has it.
async function loadResult(st: Status) {
  const revision = st.result_revision;
  const j = state.frame;
  const frame = api.frame(j);
  frame.catch(() => undefined); // a failed frame is asked for again by showFrame
  const needMesh = !state.mesh || st.domain === undefined || st.domain !== state.meshDomain;
  mark(`result ${revision}: frame ${j} asked${needMesh ? ", mesh asked" : ""}`);
  const mesh = needMesh ? await api.mesh() : undefined;
  if (mesh) mark(`mesh ${mesh.domain}`);
  let f: Frame | undefined;
  try {
    f = await frame;
    mark(`frame ${f.revision}`);
  } catch {
    // showFrame asks again and says why
  }
  // The page moves to the new result at once, with its frame (no empty picture between).
  state.resultRevision = revision;
  resultSession = st.session;
  state.frames.clear();
  if (f && f.revision === revision) state.frames.set(j, f);
  if (mesh) {
    // Dye placed on another domain means nothing on this one.
    if (state.meshDomain !== undefined && mesh.domain !== state.meshDomain && (lcs.seeds.length || lcs.lines.length)) {
      lcs.seeds = [];
      lcs.lines = [];
      say("the domain changed: the dye seeds and timelines were removed");
    }
    state.mesh = mesh;
    state.meshDomain = mesh.domain;
    setupDomainView();
  }
  await showFrame(state.frame);
  mark(`shown ${revision}`);
}

// The shown frame of a solve under way, drawn at once.
async function loadPreview() {
  try {
    const f = await api.preview();
    mark(`preview ${f.revision}`);
    if (f.revision <= state.resultRevision || f.frame !== state.frame) return;
    state.preview = f;
    if (!planar() && surface) {
      surface.setFrame(f, markers());
      state.shownRevision = f.revision;
    }
    redraw();
  } catch (e) {
    if (!(e instanceof ApiError && e.status === 404)) throw e; // 404: the result came first
  }
}

// The field drawn for the current frame: the newer preview, else the result's frame.
function shownFrame(): Frame | undefined {
  const p = state.preview;
  const f = state.frames.get(state.frame);
  if (p && p.frame === state.frame && (p.revision > state.resultRevision || (p.revision === state.resultRevision && !f))) return p;
  return f;
}

let analysisLoading = -1;
async function loadAnalysis(revision: number) {
  if (analysisLoading === revision) return;
  analysisLoading = revision;
  try {
    const analysis = await api.analysis();
    // A newer result came meanwhile: its analysis comes with a later status.
    if (analysis.revision !== state.resultRevision) return;
    state.analysis = analysis;
    state.analysisRevision = analysis.revision;
    showAnalysis(analysis);
    if (!planar()) surface?.setOrbits(orbitsAt(analysis, state.frame));
    mark(`analysis shown ${analysis.revision}`);
  } catch (e) {
    if (!(e instanceof ApiError && e.status === 409)) say((e as Error).message, true);
  } finally {
    if (analysisLoading === revision) analysisLoading = -1;
  }
}

function showAnalysis(analysis: Analysis) {
  const g = state.mesh?.grid;
  // The space-time view is of planar domains (a surface × time has no picture in 3-D).
  $("spacetime").hidden = !g;
  $("spacetime-title").hidden = !g;
  const range: [number, number] = [analysis.times[0], analysis.times[analysis.times.length - 1]];
  if (g) spacetime.set(analysis, g.min, g.max, range);
  // On surfaces: the paths through time on the mesh and in the time strip.
  $("timestrip").hidden = !!g;
  $("timestrip-title").hidden = !!g;
  if (!g) {
    strip.set(analysis, range);
    showSurfacePaths();
  }
  coherence.set(analysis.times, analysis.coherence);
  listBifurcations();
  spacetime.setTime(currentTime());
  coherence.setTime(currentTime());
  strip.setTime(currentTime());
  refreshLcs();
}

function setupDomainView() {
  const isPlanar = state.mesh!.planar;
  canvas.hidden = !isPlanar;
  surfaceLegend.hidden = true;
  const host = $("surface");
  host.hidden = isPlanar;
  if (!isPlanar) {
    if (!surface) {
      surface = new SurfaceView(host);
      surface.onPick = surfacePick;
      surface.onStroke = surfaceStroke;
      surface.grab = surfaceGrab;
      surface.setMode($<HTMLSelectElement>("preview-mode").value as SurfaceMode);
    }
    surface.setMesh(state.mesh!);
    showDesignCurves();
    showLcsOnSurface();
  }
}

async function frameData(j: number): Promise<Frame> {
  let f = state.frames.get(j);
  if (!f) {
    f = await api.frame(j);
    if (f.revision === state.resultRevision) state.frames.set(j, f);
  }
  return f;
}

async function showFrame(j: number) {
  state.frame = j;
  slider.value = String(j);
  $("time-label").textContent = `t = ${currentTime().toFixed(3)}`;
  coherence.setTime(currentTime());
  spacetime.setTime(currentTime());
  strip.setTime(currentTime());
  if (state.resultRevision < 0) return redraw();
  try {
    const f = await frameData(j);
    if (f.frame !== state.frame) return;
    if (!planar() && surface) {
      surface.setFrame(f, markers());
      surface.setOrbits(orbitsAt(state.analysis, j));
      state.shownRevision = f.revision;
      showDesignCurves();
    }
  } catch (e) {
    if (!(e instanceof ApiError && e.status === 409)) say((e as Error).message, true);
  }
  redraw();
  refreshLcs();
}

function listBifurcations() {
  const host = $("bifurcations");
  host.innerHTML = "";
  const a = state.analysis!;
  a.bifurcations.forEach((b, i) => {
    const row = document.createElement("div");
    row.className = "bifurcation" + (i === state.selectedBifurcation ? " selected" : "");
    row.textContent = `${b.kind}${b.criticality ? ` (${b.criticality})` : ""} at t = ${b.t.toFixed(3)} (${b.position.slice(0, planar() ? 2 : 3).map((v) => (Math.abs(v) < 0.005 ? 0 : v).toFixed(2)).join(", ")})`;
    const go = document.createElement("button");
    go.textContent = "go to";
    go.onclick = () => {
      selectBifurcation(i);
      say(`bifurcation ${i} picked: the Move bifurcation tool moves it to a click at the current time`);
      void showFrame(S.frameOf(scene(), b.t));
    };
    const remove = document.createElement("button");
    remove.textContent = "remove";
    remove.className = "remove-bifurcation";
    remove.onclick = () => void edit(S.removeBifurcationEdit(b.position.slice(0, planar() ? 2 : 3), b.t));
    const move = document.createElement("button");
    move.textContent = "move to current t";
    move.title = "Move this bifurcation to the current time (same place)";
    move.onclick = () => {
      const p = rounded(b.position.slice(0, planar() ? 2 : 3));
      void edit(S.moveBifurcationEdit(p, b.t, p, Number(currentTime().toFixed(4))));
    };
    // A Hopf event is reported, not edited: the edits remove and move saddle–node bifurcations.
    if (b.kind === "hopf") row.append(go);
    else row.append(go, remove, move);
    host.appendChild(row);
  });
  if (a.bifurcations.length === 0) host.textContent = "no bifurcations";
}

function selectBifurcation(i: number) {
  state.selectedBifurcation = i;
  spacetime.highlight(i);
  strip.highlight(i);
  if (!planar() && surface && state.analysis) showSurfacePaths();
  listBifurcations();
}
// A clicked bifurcation's scale on the shown mesh (S.clickedBifurcationScale); the mean edge
// length measured once per mesh.
let edgeOf: { mesh?: MeshData; h: number } = { h: 0 };
function clickScale(type: string): number {
  const m = state.mesh;
  if (!m) return 0.25;
  if (edgeOf.mesh !== m) edgeOf = { mesh: m, h: S.meanEdgeLength(m.vertices, m.faces) };
  return S.clickedBifurcationScale(type, edgeOf.h);
}
function showSurfacePaths() {
  const a = state.analysis!;
  surface?.setPaths($<HTMLInputElement>("show-paths").checked ? a : undefined, [a.times[0], a.times[a.times.length - 1]], state.selectedBifurcation);
}
strip.onPickBifurcation = (i) => {
  selectBifurcation(i);
  const b = state.analysis!.bifurcations[i];
  say(`bifurcation ${i}: ${b.kind} at t = ${b.t.toFixed(3)}: "remove" in the list, or the Move bifurcation tool and a click where it should go`);
  void showFrame(S.frameOf(scene(), b.t));
};
strip.onPickTime = (t, what) => {
  if (what !== "time") say(`${what} at t = ${t.toFixed(3)}`);
  void showFrame(S.frameOf(scene(), t));
};
spacetime.onPick = (i) => {
  selectBifurcation(i);
  const b = state.analysis!.bifurcations[i];
  say(`bifurcation ${i}: ${b.kind} at t = ${b.t.toFixed(3)}: "remove" in the list, or the Move bifurcation tool and a click where it should go`);
};

// ---- drawing the planar canvas ----------------------------------------------------------

// Boxes on the surface: the elements' handles, and with the deform generator its base
// field's singular elements and the deformed streamlines' seeds.
function markers(): number[][] {
  const deform = scene().generator === "deform" ? (scene().deform as S.DeformBlock | undefined) : undefined;
  const base = (deform?.base?.elements ?? []).flatMap((e) => (e.kind === "singular" ? [e.path[0].slice(0, -1)] : []));
  return [...S.handles(scene(), currentTime()).map((h) => h.position), ...base, ...S.deformSeeds(scene())];
}

function redraw() {
  if (!state.scene || !planar()) return;
  const v = view();
  const s = state.drag?.scene ?? scene();
  const t = currentTime();
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  const f = shownFrame();
  state.shownRevision = f?.revision ?? -1;
  const mode = $<HTMLSelectElement>("preview-mode").value;
  if (f && state.mesh?.grid) {
    const g = state.mesh.grid;
    const field: GridField = { nx: g.size[0], ny: g.size[1], min: g.min, max: g.max, vectors: f.vectors };
    if (mode !== "arrows") {
      planarPreview.setField(field, f);
      const [x0, y0] = v.toCanvas([g.min[0], g.max[1]]);
      const [x1, y1] = v.toCanvas([g.max[0], g.min[1]]);
      ctx.imageSmoothingEnabled = true;
      ctx.drawImage(planarPreview.canvas, x0, y0, x1 - x0, y1 - y0);
    }
    lcs.drawField(ctx, v, g);
    if (mode !== "texture") drawArrows(ctx, v, field, mode === "both" ? "#f97316" : "#334155");
  }
  const line = (pts: number[][], color: string, width = 2, dash: number[] = []) => {
    if (pts.length < 2) return;
    ctx.strokeStyle = color;
    ctx.lineWidth = width;
    ctx.setLineDash(dash);
    ctx.beginPath();
    pts.forEach((p, i) => {
      const [x, y] = v.toCanvas(p);
      if (i === 0) ctx.moveTo(x, y);
      else ctx.lineTo(x, y);
    });
    ctx.stroke();
    ctx.setLineDash([]);
  };
  // Design elements.
  for (const e of s.elements ?? []) {
    if (e.kind === "singular") {
      line(e.path, "#0f172a", 1.5, [5, 4]);
      const p = S.singularPosition(e, t);
      if (p) ring(v, p, typeColor(e.type ?? "saddle"), 9);
    } else if (e.kind === "regular") {
      line(e.pathline, PATHLINE_COLOR, 3);
      for (const q of e.pathline) dot(v, q, PATHLINE_COLOR, 3);
      const p = S.singularPosition({ kind: "singular", path: e.pathline }, t);
      if (p) ring(v, p, PATHLINE_COLOR, 6);
    } else if (e.kind === "streakline") {
      // The sketch (solid at its time t, dashed otherwise) and its seed.
      line(e.points, STREAKLINE_COLOR, 3, Math.abs(e.t - t) < 0.02 ? [] : [6, 4]);
      for (const q of e.points) dot(v, q, STREAKLINE_COLOR, 3);
      ring(v, e.points[0], STREAKLINE_COLOR, 7);
    } else {
      const [x, y] = v.toCanvas(e.at);
      const r = 8 + (Math.abs(e.at[e.at.length - 1] - t) < 0.02 ? 3 : 0);
      ctx.fillStyle = BIFURCATION_COLOR;
      ctx.beginPath();
      ctx.moveTo(x, y - r);
      ctx.lineTo(x + r, y);
      ctx.lineTo(x, y + r);
      ctx.lineTo(x - r, y);
      ctx.closePath();
      ctx.fill();
      const a = e.angle;
      line([e.at, [e.at[0] + e.scale * Math.cos(a), e.at[1] + e.scale * Math.sin(a)]], BIFURCATION_COLOR, 2);
    }
  }
  // Deformed streamlines: the seed, and each key's move.
  const deform = s.deform as S.DeformBlock | undefined;
  for (const e of deform?.base?.elements ?? []) if (e.kind === "singular") ring(v, e.path[0].slice(0, -1), typeColor(e.type ?? "saddle"), 9);
  for (const sl of deform?.streamlines ?? []) {
    square(v, sl.seed, PATHLINE_COLOR);
    for (const k of sl.keys) line([sl.seed, [sl.seed[0] + k.translate[0], sl.seed[1] + k.translate[1]]], PATHLINE_COLOR, 2, [4, 3]);
  }
  const j = state.frame;
  for (const k of s.keyframes ?? []) {
    if (S.frameOf(s, k.t) !== j) continue;
    for (const e of k.elements ?? []) square(v, e.at, typeColor(e.type ?? "saddle"));
    for (const sl of k.streamlines ?? []) line(sl.points, STREAMLINE_COLOR, 3);
  }
  // Links at this key frame: a dashed line to the partner, where the other key frame has it.
  for (const [here, there] of linksAtFrame(s, j)) {
    line([here, there], LINK_COLOR, 2, [6, 4]);
    dot(v, there, LINK_COLOR, 4);
  }
  if (state.linkFrom?.kind === "keyframe") {
    const e = s.keyframes?.[state.linkFrom.key];
    const at = e?.elements?.[state.linkFrom.index]?.at;
    if (e && at && S.frameOf(s, e.t) === j) ring(v, at, LINK_COLOR, 15);
  }
  // The periodic orbits the analysis found at this frame (under the singularities' dots).
  for (const o of orbitsAt(state.analysis, j)) line(o.points, o.color, 2.5);
  // Singularities of the field at this frame.
  for (const sg of f?.singularities ?? []) dot(v, sg.position, typeColor(sg.type), 6, "#fff");
  for (const p of state.cancelPicks) ring(v, p, "#111827", 12);
  if (state.selected) {
    const h = S.handles(s, t).find((x) => JSON.stringify(x.handle) === JSON.stringify(state.selected));
    if (h) ring(v, h.position, "#f97316", 14);
  }
  if (state.stroke) line(state.stroke, "#f97316", 2);
  // An interval's "show where": the two paths that could not be kept apart.
  for (const p of state.wrongPlace?.at ?? []) ring(v, p.slice(0, 2), WRONG_PLACE_COLOR, 16);
  lcs.drawMarks(ctx, v);
}

function dot(v: View, p: number[], color: string, r: number, outline?: string) {
  const [x, y] = v.toCanvas(p);
  ctx.fillStyle = color;
  ctx.beginPath();
  ctx.arc(x, y, r, 0, 2 * Math.PI);
  ctx.fill();
  if (outline) {
    ctx.strokeStyle = outline;
    ctx.lineWidth = 1.5;
    ctx.stroke();
  }
}
function ring(v: View, p: number[], color: string, r: number) {
  const [x, y] = v.toCanvas(p);
  ctx.strokeStyle = color;
  ctx.lineWidth = 2.5;
  ctx.beginPath();
  ctx.arc(x, y, r, 0, 2 * Math.PI);
  ctx.stroke();
}
function square(v: View, p: number[], color: string) {
  const [x, y] = v.toCanvas(p);
  ctx.strokeStyle = color;
  ctx.lineWidth = 3;
  ctx.strokeRect(x - 9, y - 9, 18, 18);
}

// The links of the key frame at frame j: [its element's position, the partner's].
const LINK_COLOR = "#7c3aed";
function linksAtFrame(s: S.Scene, j: number): [number[], number[]][] {
  const at = (end: [number, number]) => s.keyframes?.[end[0]]?.elements?.[end[1]]?.at;
  const out: [number[], number[]][] = [];
  for (const l of S.keyframeLinks(s)) {
    const a = at(l.from), b = at(l.to);
    if (!a || !b) continue;
    if (S.frameOf(s, s.keyframes![l.from[0]].t) === j) out.push([a, b]);
    if (S.frameOf(s, s.keyframes![l.to[0]].t) === j) out.push([b, a]);
  }
  return out;
}

// The segment from a to b with its inner points moved to the nearest mesh vertex (a line
// drawn over the surface, where the chord between two surface points runs inside it).
function overSurface(a: number[], b: number[], n = 24): number[][] {
  const v = state.mesh?.vertices ?? [];
  const out: number[][] = [a];
  for (let k = 1; k < n; ++k) {
    const x = a.map((ai, i) => ai + ((b[i] - ai) * k) / n);
    let best = -1;
    let bestD = Infinity;
    for (let i = 0; 3 * i < v.length; ++i) {
      const d = (v[3 * i] - x[0]) ** 2 + (v[3 * i + 1] - x[1]) ** 2 + (v[3 * i + 2] - x[2]) ** 2;
      if (d < bestD) (bestD = d), (best = i);
    }
    if (best >= 0) out.push([v[3 * best], v[3 * best + 1], v[3 * best + 2]]);
  }
  out.push(b);
  return out.filter((p, k) => k === 0 || p.some((x, i) => x !== out[k - 1][i]));
}

// ---- interaction ------------------------------------------------------------------------

function selectedType() {
  return $<HTMLSelectElement>("singular-type").value;
}
function lifeSpan(): [number, number] {
  return [Number($<HTMLInputElement>("life-start").value), Number($<HTMLInputElement>("life-end").value)];
}
function keyframeMode() {
  return $<HTMLInputElement>("keyframe-mode").checked;
}

function eventWorld(e: PointerEvent): number[] {
  const r = canvas.getBoundingClientRect();
  return rounded(view().toWorld(((e.clientX - r.left) * canvas.width) / r.width, ((e.clientY - r.top) * canvas.height) / r.height));
}

function nearestSingularity(p: number[], radius: number): number[] | undefined {
  const f = state.frames.get(state.frame);
  let best: number[] | undefined;
  let bestD = radius;
  for (const s of f?.singularities ?? []) {
    const d = Math.hypot(...p.map((v, k) => v - s.position[k]));
    if (d < bestD) {
      bestD = d;
      best = s.position;
    }
  }
  return best ? rounded(best) : undefined;
}

function pickForCancel(p: number[], radius: number) {
  const s = nearestSingularity(p, radius);
  if (!s) return say("click closer to a singularity (the filled dots)", true);
  state.cancelPicks.push(s);
  redraw();
  if (state.cancelPicks.length === 2) {
    const [a, b] = state.cancelPicks;
    state.cancelPicks = [];
    void edit(S.cancelEdit(state.frame, a, b));
  } else {
    say("now click the other singularity of the pair");
  }
}

// Link tool: a key-frame element at one key frame, then its partner at the next or the
// previous one.
function pickForLink(p: number[], radius: number) {
  const t = currentTime();
  let best: S.Handle | undefined;
  let bestD = radius;
  for (const h of S.handles(scene(), t)) {
    if (h.handle.kind !== "keyframe") continue;
    const d = Math.hypot(...h.position.map((x, k) => x - p[k]));
    if (d <= bestD) (bestD = d), (best = h.handle);
  }
  if (!best || best.kind !== "keyframe")
    return say("click a key-frame singularity (a square) at a key frame: move the time slider onto a key frame's tick", true);
  const name = (h: S.Handle & { kind: "keyframe" }) => `keyframes[${h.key}].elements[${h.index}]`;
  const from = state.linkFrom;
  if (!from || from.kind !== "keyframe" || (from.key === best.key && from.index === best.index)) {
    state.linkFrom = from && from.kind === "keyframe" && from.key === best.key && from.index === best.index ? undefined : best;
    redraw();
    return say(state.linkFrom ? `${name(best)} picked: go to the next (or previous) key frame and click its partner` : "link unpicked");
  }
  state.linkFrom = undefined;
  const [a, b] = from.key <= best.key ? [from, best] : [best, from];
  void change((s) => S.linkKeyframeElements(s, a, b), `${name(a)} is carried into ${name(b)} (topology kept between key frames)`);
}

canvas.addEventListener("pointerdown", (e) => {
  if (!state.scene || !planar()) return;
  canvas.setPointerCapture(e.pointerId);
  const p = eventWorld(e);
  const radius = view().worldLength(12);
  if (state.tool === "select") {
    state.selected = S.pick(scene(), currentTime(), p, radius);
    if (state.selected) state.drag = { handle: state.selected, scene: scene() };
    redraw();
  } else if (state.tool === "cancel") {
    pickForCancel(p, view().worldLength(20));
  } else if (state.tool === "link") {
    pickForLink(p, radius);
  } else if (state.tool === "move-bifurcation") {
    const b = state.analysis?.bifurcations[state.selectedBifurcation];
    if (!b) return say("pick a bifurcation first: click it in the space-time view or press go to in the list", true);
    const t = Number(currentTime().toFixed(4));
    void edit(S.moveBifurcationEdit(rounded(b.position.slice(0, 2)), b.t, p, t));
  } else {
    state.stroke = [p];
  }
});

canvas.addEventListener("pointermove", (e) => {
  if (!state.scene || !planar()) return;
  const p = eventWorld(e);
  if (state.drag) {
    state.drag.scene = S.moveHandle(scene(), state.drag.handle, p);
    redraw();
  } else if (state.stroke) {
    const last = state.stroke[state.stroke.length - 1];
    if (Math.hypot(p[0] - last[0], p[1] - last[1]) > view().worldLength(4)) {
      state.stroke.push(p);
      redraw();
    }
  }
});

canvas.addEventListener("pointerup", (e) => {
  if (!state.scene || !planar()) return;
  const p = eventWorld(e);
  if (state.drag) {
    const d = state.drag;
    state.drag = undefined;
    if (JSON.stringify(d.scene) !== JSON.stringify(scene())) void change((s) => S.moveHandle(s, d.handle, p), "moved");
    return;
  }
  const stroke = state.stroke;
  state.stroke = undefined;
  if (!stroke) return;
  if (Math.hypot(p[0] - stroke[stroke.length - 1][0], p[1] - stroke[stroke.length - 1][1]) > 1e-9) stroke.push(p);
  const isClick = stroke.length < 2 || Math.hypot(p[0] - stroke[0][0], p[1] - stroke[0][1]) < view().worldLength(6);
  const t = Number(currentTime().toFixed(4));
  const [ts, te] = lifeSpan();
  if (deformIgnores(state.tool === "singular" ? selectedType() : state.tool)) return redraw();
  try {
    const type = selectedType();
    if (state.tool === "singular") {
      if (keyframeMode()) void change((s) => S.addKeyframeSingular(s, t, type, stroke[0]), `${type} in the key frame at t = ${t}`);
      else if (isClick) void change((s) => S.addSingular(s, type, stroke[0], undefined, ts), `fixed ${type} placed`);
      // A drag: the element moves along the dragged curve (a few of its points).
      else void change((s) => S.addSingularPath(s, type, resample(stroke, 6), ts, te), `${type} moving along the drawn curve from t = ${ts} to ${te}`);
    } else if (state.tool === "dye") {
      // A click: a streakline's seed; a drag: a timeline, the segment at this time.
      if (isClick) lcs.seeds.push(stroke[0]);
      else lcs.lines.push({ line: [stroke[0], p], t: currentTime() });
      refreshLcs();
    } else if (state.tool === "pathline") {
      if (isClick) return say("drag to draw a pathline", true);
      void change((s) => S.addPathline(s, resample(stroke, 6), ts, te), `pathline from t = ${ts} to ${te}`);
    } else if (state.tool === "streakline") {
      if (isClick) return say("drag from the seed to draw the streakline the dye should form at the current time", true);
      void change((s) => S.addStreakline(s, resample(stroke, 12), t), `streakline sketched at t = ${t}`);
    } else if (state.tool === "streamline") {
      if (isClick) return say("drag to draw a streamline", true);
      void change((s) => S.addKeyframeStreamline(s, t, resample(stroke, 8)), `streamline in the key frame at t = ${t}`);
    } else if (state.tool === "deform") {
      if (isClick) return say("drag from the streamline's seed to where it should be at the current time", true);
      const turn = Number($<HTMLInputElement>("deform-turn").value) || 0;
      const d = rounded([p[0] - stroke[0][0], p[1] - stroke[0][1]]);
      void change((s) => S.addDeformStreamline(s, stroke[0], d, t, turn), `streamline from (${stroke[0].join(", ")}) moved by (${d.join(", ")}) at t = ${t}`);
    } else if (state.tool === "bifurcation") {
      const kind = $<HTMLSelectElement>("bifurcation-type").value;
      const { scale, angle } = S.bifurcationAxis(isClick ? undefined : [p[0] - stroke[0][0], p[1] - stroke[0][1]], clickScale(kind));
      void change((s) => S.addBifurcation(s, kind, stroke[0], t, scale, angle), `${kind} at t = ${t}`);
    }
  } catch (err) {
    say((err as Error).message, true);
  }
  redraw();
});

// The deform generator turns its base design (deform.base: the elements placed before the
// field was deformed) and ignores the scene's elements and key frames, so the tools that
// would add one there say so and add nothing (true). `what`: the thing not added.
const ADDS_ELEMENTS = ["singular", "pathline", "streakline", "streamline", "bifurcation"];
function deformIgnores(what: string): boolean {
  if (!state.scene || scene().generator !== "deform" || !ADDS_ELEMENTS.includes(state.tool)) return false;
  say(`not added: the deform generator ignores new elements and key frames (it turns its base design), so this ${what} would change nothing; choose another generator to design with it`, true);
  return true;
}

function surfacePick(p: number[]) {
  if (!state.scene) return;
  if (deformIgnores(state.tool === "singular" ? selectedType() : state.tool)) return;
  const at = rounded(p);
  const t = Number(currentTime().toFixed(4));
  const type = selectedType();
  if (state.tool === "singular") {
    const t0 = lifeSpan()[0];
    if (keyframeMode()) void change((s) => S.addKeyframeSingular(s, t, type, at), `${type} in the key frame at t = ${t}`);
    else void change((s) => S.addSingular(s, type, at, undefined, t0), `fixed ${type} placed`);
  } else if (state.tool === "bifurcation") {
    const kind = $<HTMLSelectElement>("bifurcation-type").value;
    const scale = clickScale(kind);
    void change((s) => S.addBifurcation(s, kind, at, t, scale), `${kind} at t = ${t}, scale ${scale} (drag on the surface to give its axis and size)`);
  } else if (state.tool === "cancel") {
    pickForCancel(at, 0.2);
  } else if (state.tool === "link") {
    pickForLink(at, 0.06 * surfaceRadius());
  } else if (state.tool === "select") {
    state.selected = surfaceHandleAt(at) ?? S.pick(scene(), t, at, 0.1);
    if (state.selected) return say("selected: drag it over the surface to move it, Delete removes it");
    // A bifurcation's diamond of the paths through time: picked, and its time shown.
    const a = state.analysis;
    const best = bifurcationAt(a, at, 0.05 * surfaceRadius());
    if (best < 0 || !a) return say("nothing here");
    selectBifurcation(best);
    const b = a.bifurcations[best];
    say(`bifurcation ${best}: ${b.kind} at t = ${b.t.toFixed(3)}: "remove" in the list, or the Move bifurcation tool and a click where it should go`);
    void showFrame(S.frameOf(scene(), b.t));
  } else if (state.tool === "move-bifurcation") {
    const b = state.analysis?.bifurcations[state.selectedBifurcation];
    if (!b) return say("pick a bifurcation first: press go to in the list", true);
    void edit(S.moveBifurcationEdit(rounded(b.position.slice(0, 3)), b.t, at, t));
  } else if (state.tool === "dye") {
    lcs.seeds.push(at);
    refreshLcs();
    say(`dye seed at (${at.join(", ")}): its streakline follows the time slider (drag on the surface for a timeline)`);
  } else if (state.tool === "streakline") {
    say("drag on the surface from the seed to draw the streakline the dye should form at the current time", true);
  } else if (state.tool === "pathline" || state.tool === "streamline") {
    say(`drag on the surface to draw a ${state.tool}`, true);
  } else if (state.tool === "deform") {
    say("drag on the surface from the streamline's seed to where it should be at the current time", true);
  }
}

// "Near" on the surface: a share of the mesh's size.
function surfaceRadius(): number {
  return boundingRadius(state.mesh?.vertices ?? []);
}
function surfaceHandleAt(p: number[]): S.Handle | undefined {
  return handleOnSurface(scene(), currentTime(), p, 0.06 * surfaceRadius());
}

// Whether a left drag from p on the surface is the tool's (else it orbits the camera):
// the drawing tools own every drag on the surface; the Select tool a drag from a handle.
function surfaceGrab(p: number[]): boolean {
  if (["pathline", "streamline", "streakline", "deform", "singular", "bifurcation", "dye"].includes(state.tool)) return true;
  if (state.tool === "select") {
    state.selected = surfaceHandleAt(p);
    return state.selected !== undefined;
  }
  return false;
}

// The Deform streamline tool on a surface: the drag's first point is the seed, its last
// where the seed should be at the current time. The key's translate is defined in the
// log-map chart around the seed (docs/scene_reference.md, deform), which the server
// computes: the browser has no exact log map.
async function surfaceDeform(points: number[][], t: number) {
  const seed = rounded(points[0]);
  const to = rounded(points[points.length - 1]);
  const turn = Number($<HTMLInputElement>("deform-turn").value) || 0;
  try {
    const { translate } = await api.seedTranslation(seed, to);
    const d = rounded(translate);
    await change((s) => S.addDeformStreamline(s, seed, d, t, turn), `streamline from (${seed.join(", ")}) moved to (${to.join(", ")}) at t = ${t}`);
  } catch (err) {
    say((err as Error).message, true);
  }
}

// The Bifurcation tool on a surface: placed where the drag starts, its pair moving
// along the drag (the axis and scale from the server's log map around the start, the
// chart the element is designed in), at the current time.
async function surfaceBifurcation(points: number[][], t: number) {
  const at = rounded(points[0]);
  const to = rounded(points[points.length - 1]);
  const kind = $<HTMLSelectElement>("bifurcation-type").value;
  try {
    const { scale, angle } = S.bifurcationAxis((await api.chartCoordinates(at, to)).coords);
    await change((s) => S.addBifurcation(s, kind, at, t, scale, angle), `${kind} at t = ${t}, its pair along the drag (scale ${scale})`);
  } catch (err) {
    say((err as Error).message, true);
  }
}

// A stroke drawn on the surface: points picked on it, [x, y, z].
function surfaceStroke(points: number[][]) {
  if (!state.scene) return;
  const t = Number(currentTime().toFixed(4));
  const [ts, te] = lifeSpan();
  if (deformIgnores(state.tool === "singular" ? selectedType() : state.tool)) return;
  try {
    if (points.length < 2) return say(`drag on the surface to draw a ${state.tool}`, true);
    if (state.tool === "singular") {
      const type = selectedType();
      if (keyframeMode()) void change((s) => S.addKeyframeSingular(s, t, type, rounded(points[0])), `${type} in the key frame at t = ${t}`);
      // The element moves along the dragged curve (a few of its points) over the life span.
      else void change((s) => S.addSingularPath(s, type, resample(points, 6).map(rounded), ts, te), `${type} moving along the curve drawn on the surface from t = ${ts} to ${te}`);
    } else if (state.tool === "select") {
      const h = state.selected;
      const to = rounded(points[points.length - 1]);
      if (h) void change((s) => S.moveHandle(s, h, to), "moved on the surface");
    } else if (state.tool === "pathline")
      void change((s) => S.addPathline(s, resample(points, 8), ts, te), `pathline on the surface from t = ${ts} to ${te}`);
    else if (state.tool === "streamline")
      void change((s) => S.addKeyframeStreamline(s, t, resample(points, 10)), `streamline on the surface in the key frame at t = ${t}`);
    else if (state.tool === "streakline")
      void change((s) => S.addStreakline(s, resample(points, 12).map(rounded), t), `streakline sketched on the surface at t = ${t}`);
    else if (state.tool === "dye") {
      // A timeline: the segment from the drag's start to its end (snapped to the surface
      // by the server), a material line at the current time.
      lcs.lines.push({ line: [rounded(points[0]), rounded(points[points.length - 1])], t: currentTime() });
      refreshLcs();
      say("timeline drawn: it is carried by the flow as the time slider moves");
    } else if (state.tool === "deform") void surfaceDeform(points, t);
    else if (state.tool === "bifurcation") void surfaceBifurcation(points, t);
  } catch (err) {
    say((err as Error).message, true);
  }
}

// A stroke drawn in the space-time view: [x, y, t] points (spacetime_draw.ts).
spacetime.onStroke = (points) => {
  if (!state.scene || !planar()) return;
  if (deformIgnores("pathline")) return;
  try {
    const g = scene().domain.grid!;
    const line = spaceTimePathline(points, { min: [g.min[0], g.min[1]], max: [g.max[0], g.max[1]], range: [scene().time.range[0], scene().time.range[1]] });
    const t0 = line[0][2];
    const t1 = line[line.length - 1][2];
    S.addTimedPathline(scene(), line); // checks the points now (throws)
    void change((s) => S.addTimedPathline(s, line), `pathline drawn in space-time, from t = ${t0} to ${t1}`);
  } catch (err) {
    say((err as Error).message, true);
  }
};

function deleteSelected() {
  if (!state.selected) return say("select an element first (Select tool)", true);
  const h = state.selected;
  state.selected = undefined;
  void change((s) => S.removeHandle(s, h), "deleted");
}

async function undo() {
  try {
    const r = await onCurrentRevision("undo", (revision) => api.undo(revision));
    if (r) {
      showScene(r);
      say("undone");
    }
  } catch (e) {
    say((e as Error).message, true);
  }
}
async function redo() {
  try {
    const r = await onCurrentRevision("redo", (revision) => api.redo(revision));
    if (r) {
      showScene(r);
      say("redone");
    }
  } catch (e) {
    say((e as Error).message, true);
  }
}

let playTimer: number | undefined;
function play(on: boolean) {
  state.playing = on;
  $("play").textContent = on ? "❚❚" : "▶";
  if (playTimer !== undefined) clearTimeout(playTimer);
  const step = async () => {
    if (!state.playing) return;
    const frames = scene().time.frames;
    const next = (state.frame + 1) % frames;
    // Ask for the frames after it while this one is drawn.
    for (let k = 1; k <= 3; ++k) void frameData((next + k) % frames).catch(() => undefined);
    await showFrame(next);
    playTimer = window.setTimeout(step, 60);
  };
  if (on) void step();
}

// ---- wiring -----------------------------------------------------------------------------

for (const t of S.SINGULAR_TYPES) $("singular-type").append(new Option(t, t));
for (const t of S.BIFURCATION_TYPES) $("bifurcation-type").append(new Option(t, t));
$<HTMLSelectElement>("singular-type").value = "ccw_center";
document.querySelectorAll<HTMLInputElement>("input[name=tool]").forEach((r) =>
  r.addEventListener("change", () => {
    state.tool = r.value;
    spacetime.drawing = state.tool === "pathline";
    state.cancelPicks = [];
    state.linkFrom = undefined;
    state.selected = undefined;
    redraw();
  }),
);
slider.addEventListener("input", () => void showFrame(Number(slider.value)));
$<HTMLSelectElement>("preview-mode").addEventListener("change", (e) => {
  surface?.setMode((e.target as HTMLSelectElement).value as SurfaceMode);
  redraw();
});
$<HTMLSelectElement>("lcs-mode").addEventListener("change", (e) => {
  lcs.direction = (e.target as HTMLSelectElement).value as typeof lcs.direction;
  refreshLcs();
});
$<HTMLInputElement>("lcs-horizon").addEventListener("change", (e) => {
  const T = Number((e.target as HTMLInputElement).value);
  if (!(T > 0)) return say("the FTLE horizon T must be a positive time", true);
  lcs.horizon = T;
  refreshLcs();
});
$("dye-clear").addEventListener("click", () => {
  lcs.seeds = [];
  lcs.lines = [];
  refreshLcs();
  redraw();
});
$<HTMLInputElement>("show-paths").addEventListener("change", () => {
  if (state.analysis && !planar()) showSurfacePaths();
});
$("play").addEventListener("click", () => play(!state.playing));
$("delete").addEventListener("click", deleteSelected);
$("undo").addEventListener("click", () => void undo());
$("redo").addEventListener("click", () => void redo());
$("rotate-field").addEventListener("click", () => {
  const theta = Number($<HTMLInputElement>("field-turn").value);
  if (!Number.isFinite(theta)) return say("give the turn in radians", true);
  void change((s) => S.setDeformTransform(s, theta), `the field turns by ${theta} rad over the time range (deform generator)`);
});
$("new").addEventListener("click", () => void change(() => S.emptyScene(), "new empty design on the 65² grid", false));
$<HTMLSelectElement>("generator").addEventListener("change", (e) => {
  const generator = (e.target as HTMLSelectElement).value;
  void change((s) => S.setGenerator(s, generator), "generator changed");
});
$<HTMLInputElement>("keep-topology").addEventListener("change", (e) => {
  const on = (e.target as HTMLInputElement).checked;
  // Shown as the scene has it until the change is made (a refused one leaves it as it was).
  (e.target as HTMLInputElement).checked = S.keyframeTopologyMatched(scene());
  void change(
    (s) => S.setKeyframeTopology(s, on),
    on
      ? "topology kept between key frames: their singularities are matched and carried, unmatched ones created or cancelled in pairs"
      : "topology between key frames left to the solve (the paper's behaviour)",
  );
});
$<HTMLSelectElement>("domain").addEventListener("change", (e) => {
  const d = (e.target as HTMLSelectElement).value;
  const domain = d === "grid" ? S.emptyScene().domain : d === "sphere" ? { sphere: { subdivisions: 4, radius: 1 } } : { torus: {} };
  void change((s) => ({ ...s, domain, elements: [], keyframes: [], edits: [], deform: undefined }), `new design on the ${d}`, false);
});
$<HTMLInputElement>("upload").addEventListener("change", async (e) => {
  const file = (e.target as HTMLInputElement).files?.[0];
  if (!file) return;
  try {
    const r = await api.upload(file);
    await change((s) => ({ ...s, domain: { mesh: r.file }, elements: [], keyframes: [], edits: [], deform: undefined }), `designing on ${r.file}`, false);
  } catch (err) {
    say((err as Error).message, true);
  }
});
sceneText.addEventListener("input", () => {
  state.jsonDirty = true;
  $("scene-dirty").textContent = "(edited: Apply to use it)";
});
$("apply-json").addEventListener("click", async () => {
  let parsed: S.Scene;
  try {
    parsed = JSON.parse(sceneText.value);
  } catch (err) {
    return say(`scene JSON: ${(err as Error).message}`, true);
  }
  state.jsonDirty = false;
  $("scene-dirty").textContent = "";
  await change(() => parsed, "scene applied", false);
});
$("export-npy").addEventListener("click", async () => {
  try {
    const r = await queue.run(() => withField(() => api.exportField("npy", "export")));
    say(`exported revision ${r.revision}: ${r.files.length} files into export/: ${r.files.join(", ")}`);
  } catch (e) {
    say((e as Error).message, true);
  }
});
$("export-vtk").addEventListener("click", async () => {
  try {
    const r = await queue.run(() => withField(() => api.exportField("vtk", "export")));
    say(`exported revision ${r.revision}: ${r.files.length} files into export/ (field.pvd opens in ParaView)`);
  } catch (e) {
    say((e as Error).message, true);
  }
});
$("render-video").addEventListener("click", async () => {
  const size = Math.round(Number($<HTMLInputElement>("video-size").value));
  if (!(size >= 16 && size <= 4096)) return say("the video size is a number of pixels in [16, 4096]", true);
  say(`rendering video.mp4 (${size}²${planar() ? "" : ", the surface from this camera"})…`);
  try {
    const camera = planar() || !surface ? undefined : surface.cameraView();
    const r = await queue.run(() => withField(() => api.render("video.mp4", size, camera)));
    const a = $<HTMLAnchorElement>("video-link");
    a.href = `api/files/${r.file}?rev=${r.revision}`;
    a.hidden = false;
    say(`rendered ${r.file} of revision ${r.revision}: ${r.frames} frames in ${r.seconds.toFixed(1)} s`);
  } catch (e) {
    say((e as Error).message, true);
  }
});
document.addEventListener("keydown", (e) => {
  if ((e.target as HTMLElement).tagName === "TEXTAREA" || (e.target as HTMLElement).tagName === "INPUT") return;
  if (e.key === "Delete" || e.key === "Backspace") deleteSelected();
  else if ((e.ctrlKey || e.metaKey) && e.key.toLowerCase() === "z") void (e.shiftKey ? redo() : undo());
  else if (e.key === " ") {
    e.preventDefault();
    play(!state.playing);
  } else if (e.key === "ArrowRight") void showFrame(Math.min(scene().time.frames - 1, state.frame + 1));
  else if (e.key === "ArrowLeft") void showFrame(Math.max(0, state.frame - 1));
});

// For the end-to-end test and the curious: the state, read-only.
(window as unknown as { tvf: unknown }).tvf = {
  state,
  marks,
  // What the status handling is doing (the e2e harness prints it when a page never settles).
  pending: () => ({ showing, nextStatus, lastStatus, analysisLoading }),
  view: () => (planar() ? view() : undefined),
  spacetime: (p: number[]) => spacetime.toScreen(p),
  spacetimeLabels: () => spacetime.timeLabels(),
  surface: (p: number[]) => surface?.toScreen(p),
  surfaceVisible: (p: number[]) => surface?.visible(p) ?? false,
  // The moving preview: paused, it steps only when asked (the tests compare two pictures
  // a known number of steps apart); ringMotion measures the motion between two pictures.
  preview: {
    pause: (on: boolean) => (ticker.paused = on),
    step: (n: number) => ticker.step(n),
  },
  ringMotion,
  // A copy of a view's picture as it is now: RGBA in device pixels, and device pixels per
  // CSS pixel (surface() and view().toCanvas() give CSS pixels). The tests read colours
  // at points with it (the surface's renderer keeps its drawing buffer, so it can be read
  // between animation frames).
  pixels: (which: "surface" | "field" = "surface") => {
    const source = which === "surface" ? document.querySelector<HTMLCanvasElement>("#surface canvas") : canvas;
    if (!source) return undefined;
    const copy = document.createElement("canvas");
    copy.width = source.width;
    copy.height = source.height;
    const g = copy.getContext("2d")!;
    g.drawImage(source, 0, 0);
    return { data: g.getImageData(0, 0, copy.width, copy.height).data, width: copy.width, height: copy.height, scale: source.width / source.clientWidth };
  },
  timestrip: (i: number) => strip.bifurcationAt(i),
  lcs,
};
ticker.start();

(async () => {
  try {
    showScene(await api.scene());
  } catch (e) {
    say((e as Error).message, true);
  }
  listen();
  void poll();
})();
