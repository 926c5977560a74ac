// The designer's Lagrangian overlays (docs/user_guide.md, "The designer's LCS overlay"):
// the finite-time Lyapunov exponent at the current time (GET /api/ftle, forward:
// repelling LCS, backward: attracting) as a magma colour map with its legend; dye:
// streaklines released from clicked seeds since the field's first time, drawn at the
// current time (POST /api/streakline); and timelines: segments drawn at some time,
// carried by the flow to the current time (POST /api/timeline). All are fetched again
// when the time or the field changes; a request overtaken by a newer one is dropped.
// On the planar view this class draws them on the canvas; on a surface the page hands
// vertexColors() and the curves (curveRuns()) to the surface view and drawLegend() to a
// small canvas over it.
import { ApiError } from "./api";
import type { View } from "./view";

export type FtleDirection = "off" | "forward" | "backward";

export interface FtleAnswer {
  revision: number;
  t: number;
  horizon: number;
  direction: string;
  span: number;
  cut: boolean;
  left: number;
  min: number | null;
  max: number | null;
  range: [number, number];
  values: (number | null)[];
  seconds: number;
}

export interface CurveAnswer {
  revision: number;
  t: number;
  points: number[][];
  gaps: number[];
  released: number;
  left: number;
  // How well the points resolve the curve (docs/file_formats.md): neighbours further apart
  // than `resolution` are drawn as straight chords; `unresolved` counts them, and
  // `unresolved_by` says what stopped the server refining them.
  resolution: number;
  largest_gap: number;
  unresolved: number;
  unresolved_by: "particles" | "torn" | null;
  seconds: number;
}

async function call<T>(method: string, path: string, body?: unknown): Promise<T> {
  const init: RequestInit = { method };
  if (body !== undefined) {
    init.body = JSON.stringify(body);
    init.headers = { "Content-Type": "application/json" };
  }
  const res = await fetch(path, init);
  const json = (await res.json().catch(() => ({ error: `${method} ${path}: HTTP ${res.status} without JSON` }))) as T & { error?: string };
  if (!res.ok) throw new ApiError(res.status, json.error ?? `HTTP ${res.status}`);
  return json;
}

export const lcsApi = {
  ftle: (t: number, horizon: number, direction: "forward" | "backward") =>
    call<FtleAnswer>("GET", `api/ftle?t=${t}&horizon=${horizon}&direction=${direction}`),
  streakline: (seed: number[], from: number, to: number) => call<CurveAnswer>("POST", "api/streakline", { seed, from, to }),
  timeline: (line: number[][], from: number, to: number) => call<CurveAnswer>("POST", "api/timeline", { line, from, to }),
};

// Magma (the colour map of tvf ftle's pictures, render/lcs_pictures.cpp), s in [0, 1].
const MAGMA = [
  [0, 0, 4],
  [28, 16, 68],
  [79, 18, 123],
  [129, 37, 129],
  [181, 54, 122],
  [229, 80, 100],
  [251, 135, 97],
  [254, 194, 135],
  [252, 253, 191],
];
export function magma(s: number): [number, number, number] {
  const x = Math.min(1, Math.max(0, s)) * (MAGMA.length - 1);
  const i = Math.min(MAGMA.length - 2, Math.floor(x));
  const f = x - i;
  const a = MAGMA[i];
  const b = MAGMA[i + 1];
  return [0, 1, 2].map((k) => Math.round(a[k] + f * (b[k] - a[k]))) as [number, number, number];
}

export const DYE_COLOR = "#16a34a";
// Where σ is undefined (the particle left the domain), as tvf ftle's pictures.
const NAN_GREY: [number, number, number] = [154, 154, 154];
export const TIMELINE_COLOR = "#0ea5e9";

export interface Grid {
  size: [number, number];
  min: [number, number];
  max: [number, number];
}

export class LcsOverlay {
  direction: FtleDirection = "off";
  horizon = 1;
  seeds: number[][] = [];
  // Timelines: segments drawn at time t, shown carried by the flow to the current time
  // (backwards in time before t).
  lines: { line: number[][]; t: number }[] = [];
  ftle?: FtleAnswer;
  dye: CurveAnswer[] = [];
  timelines: CurveAnswer[] = [];
  // Milliseconds of the last FTLE update, from the request to the picture (the e2e test reports it).
  lastUpdateMs = 0;
  error = "";
  private image?: HTMLCanvasElement;
  private ticket = 0;
  private dyeTicket = 0;

  // The sentences handed to onError that still stand (the FTLE's, the dye's): once that
  // part works again, onCleared takes each back (the page's status line showed a refused
  // horizon after a good one had drawn its picture).
  private reported: { ftle?: string; dye?: string } = {};

  constructor(
    private readonly onChange: () => void,
    private readonly onError: (message: string) => void,
    private readonly onCleared: (message: string) => void = () => {},
  ) {}

  private report(part: "ftle" | "dye", message: string) {
    this.reported[part] = message;
    this.onError(message);
  }
  private cleared(part: "ftle" | "dye") {
    const m = this.reported[part];
    this.reported[part] = undefined;
    if (m !== undefined) this.onCleared(m);
  }

  // The current time or field changed (or the settings): fetch what is shown again.
  // `grid`: the planar domain's grid (the FTLE becomes a picture over it); undefined on a
  // surface (the values are per vertex, coloured by vertexColors()).
  async update(t: number, t0: number, grid: Grid | undefined) {
    await Promise.all([this.updateFtle(t, grid), this.updateDye(t, t0)]);
  }

  // One FTLE request at a time: while one runs, only the newest asked-for time waits
  // (scrubbing does not queue up a computation per frame on the server).
  private inFlight = false;
  private pending?: { t: number; grid: Grid | undefined };
  private async updateFtle(t: number, grid: Grid | undefined) {
    if (this.inFlight && this.direction !== "off") {
      this.pending = { t, grid };
      return;
    }
    this.inFlight = true;
    try {
      await this.fetchFtle(t, grid);
    } finally {
      this.inFlight = false;
    }
    const next = this.pending;
    this.pending = undefined;
    if (next) await this.updateFtle(next.t, next.grid);
  }

  private async fetchFtle(t: number, grid: Grid | undefined) {
    const ticket = ++this.ticket;
    if (this.direction === "off") {
      this.ftle = undefined;
      this.image = undefined;
      this.onChange();
      return;
    }
    const start = performance.now();
    try {
      const a = await lcsApi.ftle(t, this.horizon, this.direction);
      if (ticket !== this.ticket) return;
      this.ftle = a;
      this.image = grid ? picture(a, grid) : undefined;
      this.lastUpdateMs = performance.now() - start;
      this.error = "";
      this.cleared("ftle");
    } catch (e) {
      if (ticket !== this.ticket) return;
      this.ftle = undefined;
      this.image = undefined;
      this.error = (e as Error).message;
      if (!(e instanceof ApiError && e.status === 409)) this.report("ftle", this.error);
    }
    this.onChange();
  }

  private async updateDye(t: number, t0: number) {
    const ticket = ++this.dyeTicket;
    if (this.seeds.length === 0 && this.lines.length === 0) {
      this.dye = [];
      this.timelines = [];
      this.onChange();  // the surface view and the notes drop what was shown
      return;
    }
    // Each seed and line on its own: one the server refuses (a seed outside the domain, a
    // line end off the surface) is dropped with its sentence, and the others stay drawn
    // (one refusal had cleared every curve, and the refused seed, kept, failed again at
    // every time).
    const seeds = this.seeds, lines = this.lines;
    const [streaks, material] = await Promise.all([
      Promise.allSettled(seeds.map((s) => lcsApi.streakline(s, t0, t))),
      Promise.allSettled(lines.map((l) => lcsApi.timeline(l.line, l.t, t))),
    ]);
    if (ticket !== this.dyeTicket) return;
    const failure = (r: PromiseSettledResult<CurveAnswer>) => (r.status === "rejected" ? (r.reason as Error) : undefined);
    // 409: the field changed meanwhile (a newer update follows); 5xx: the server's fault.
    const stale = (e: Error) => e instanceof ApiError && e.status === 409;
    const refused = (r: PromiseSettledResult<CurveAnswer>) => {
      const e = failure(r);
      return e instanceof ApiError && !stale(e) && e.status < 500;
    };
    // Only what these results judged: seeds and lines added meanwhile stay.
    this.seeds = this.seeds.filter((s) => { const i = seeds.indexOf(s); return i < 0 || !refused(streaks[i]); });
    this.lines = this.lines.filter((l) => { const i = lines.indexOf(l); return i < 0 || !refused(material[i]); });
    const kept = (all: PromiseSettledResult<CurveAnswer>[]) => all.flatMap((r) => (r.status === "fulfilled" ? [r.value] : []));
    this.dye = kept(streaks);
    this.timelines = kept(material);
    const failures = [...streaks, ...material].flatMap((r) => failure(r) ?? []);
    const shown = failures.find((e) => !stale(e));
    if (shown) this.report("dye", shown.message);
    else if (failures.length === 0) this.cleared("dye");
    this.onChange();
  }

  // The FTLE picture over the grid's box, under the design's marks.
  drawField(ctx: CanvasRenderingContext2D, v: View, grid: Grid) {
    if (!this.image || !this.ftle) return;
    const [x0, y0] = v.toCanvas([grid.min[0], grid.max[1]]);
    const [x1, y1] = v.toCanvas([grid.max[0], grid.min[1]]);
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(this.image, x0, y0, x1 - x0, y1 - y0);
  }

  // The dye lines and seeds, and the FTLE legend.
  drawMarks(ctx: CanvasRenderingContext2D, v: View) {
    ctx.lineWidth = 2.5;
    for (const d of [...this.dye, ...this.timelines]) {
      ctx.strokeStyle = this.dye.includes(d) ? DYE_COLOR : TIMELINE_COLOR;
      ctx.beginPath();
      for (const run of curveRuns(d))
        run.forEach((p, i) => {
          const [x, y] = v.toCanvas(p);
          if (i === 0) ctx.moveTo(x, y);
          else ctx.lineTo(x, y);
        });
      ctx.stroke();
    }
    for (const s of this.seeds) {
      const [x, y] = v.toCanvas(s);
      ctx.fillStyle = DYE_COLOR;
      ctx.strokeStyle = "#fff";
      ctx.lineWidth = 1.5;
      ctx.beginPath();
      ctx.arc(x, y, 5, 0, 2 * Math.PI);
      ctx.fill();
      ctx.stroke();
    }
    if (this.ftle) drawLegend(ctx, this.ftle);
  }

  // The dye's curves, streaklines first: each an unbroken run of points with its colour
  // (for the surface view).
  curves(): { points: number[][]; color: string }[] {
    const out: { points: number[][]; color: string }[] = [];
    for (const d of this.dye) for (const points of curveRuns(d)) out.push({ points, color: DYE_COLOR });
    for (const d of this.timelines) for (const points of curveRuns(d)) out.push({ points, color: TIMELINE_COLOR });
    return out;
  }
}

// One line per dye streakline or timeline the server could not resolve (neighbours left
// further apart than its resolution, drawn as straight chords), saying which and why; none
// when every curve is resolved. Dye lines are numbered in the order their seeds were
// placed, timelines in the order they were drawn.
export function unresolvedNotes(dye: CurveAnswer[], timelines: CurveAnswer[]): string[] {
  const g = (x: number) => String(Number(x.toPrecision(3)));
  const note = (what: string, c: CurveAnswer, torn: string, particles: string) => {
    const pairs = `${c.unresolved} neighbour${c.unresolved > 1 ? "s are" : " is"} further apart than ${g(c.resolution)} (up to ${g(c.largest_gap)}), drawn as straight lines`;
    const why = c.unresolved_by === "torn" ? `the flow tears it apart (${torn} end up that far apart)` : particles;
    return `${what} at t = ${g(c.t)}: ${pairs}; ${why}`;
  };
  const out: string[] = [];
  dye.forEach((c, i) => {
    if (c.unresolved > 0)
      out.push(note(`dye ${i + 1}`, c, "releases within 1e-12 of each other in time", "more than the server's 20,000 added releases are needed"));
  });
  timelines.forEach((c, i) => {
    if (c.unresolved > 0)
      out.push(note(`timeline ${i + 1}`, c, "particles within 1e-12 of each other on the line", "more than the server's 20,000 particles are needed"));
  });
  return out;
}

// A streakline or timeline cut where particles left the domain (its `gaps`: the indices
// of the points that start a new piece): the unbroken runs of points, in order. A run
// may have a single point.
export function curveRuns(c: { points: number[][]; gaps: number[] }): number[][][] {
  const gaps = new Set(c.gaps);
  const runs: number[][][] = [];
  c.points.forEach((p, i) => {
    if (i === 0 || gaps.has(i)) runs.push([]);
    runs[runs.length - 1].push(p);
  });
  return runs;
}

// The FTLE's colour at each vertex (a surface's overlay): magma over the answer's colour
// range, r, g, b in [0, 1] per vertex (3 numbers each); grey where σ is undefined, as in
// the planar picture and tvf ftle.
export function vertexColors(a: FtleAnswer): Float32Array {
  const out = new Float32Array(3 * a.values.length);
  const [lo, hi] = a.range;
  const scale = hi > lo ? 1 / (hi - lo) : 0;
  a.values.forEach((v, i) => {
    const c = v === null ? NAN_GREY : magma((v - lo) * scale);
    for (let k = 0; k < 3; ++k) out[3 * i + k] = c[k] / 255;
  });
  return out;
}

// One pixel per grid vertex, the image's rows top (max y) down; NaN grey as in tvf ftle.
function picture(a: FtleAnswer, grid: Grid): HTMLCanvasElement {
  const [nx, ny] = grid.size;
  const c = document.createElement("canvas");
  c.width = nx;
  c.height = ny;
  const g = c.getContext("2d")!;
  const img = g.createImageData(nx, ny);
  const [lo, hi] = a.range;
  const scale = hi > lo ? 1 / (hi - lo) : 0;
  for (let iy = 0; iy < ny; ++iy)
    for (let ix = 0; ix < nx; ++ix) {
      const v = a.values[iy * nx + ix];
      const k = 4 * ((ny - 1 - iy) * nx + ix);
      const [r, gg, b] = v === null ? NAN_GREY : magma((v - lo) * scale);
      img.data[k] = r;
      img.data[k + 1] = gg;
      img.data[k + 2] = b;
      img.data[k + 3] = 255;
    }
  g.putImageData(img, 0, 0);
  return c;
}

// The colour bar in the lower left corner: the range, the direction and the horizon.
export function drawLegend(ctx: CanvasRenderingContext2D, a: FtleAnswer) {
  const x = 10;
  const y = ctx.canvas.height - 46;
  const w = 160;
  ctx.fillStyle = "rgba(255,255,255,0.85)";
  ctx.fillRect(x - 6, y - 18, w + 12, 54);
  const labels = legendLabels(a);
  ctx.font = "11px sans-serif";
  ctx.textAlign = "left";
  if (a.span <= 0) {
    // No window (every value undefined, the picture grey): words, not a bar claiming a range.
    ctx.fillStyle = "#111827";
    ctx.fillText(labels.title, x, y - 5);
    ctx.fillText(labels.low, x, y + 12);
    return;
  }
  for (let i = 0; i < w; ++i) {
    const [r, g, b] = magma(i / (w - 1));
    ctx.fillStyle = `rgb(${r},${g},${b})`;
    ctx.fillRect(x + i, y, 1, 12);
  }
  ctx.fillStyle = "#111827";
  ctx.fillText(labels.title, x, y - 5);
  ctx.fillText(labels.low, x, y + 26);
  ctx.textAlign = "right";
  ctx.fillText(labels.high, x + w, y + 26);
  ctx.textAlign = "left";
}

// The legend's words: the direction and horizon, and the colour range's ends.
export function legendLabels(a: FtleAnswer): { title: string; low: string; high: string } {
  // At the end of the time range (forward) or its start (backward) there is no time to
  // integrate over: every value is undefined.
  if (a.span <= 0)
    return {
      title: `FTLE ${a.direction}: none at t = ${Number(a.t.toFixed(4))}`,
      low: `no time ${a.direction === "backward" ? "before" : "after"} it in the field's range`,
      high: "",
    };
  return {
    title: `FTLE ${a.direction}, T = ${a.span < a.horizon ? `${a.span.toFixed(3)} (cut)` : a.horizon}`,
    low: a.range[0].toPrecision(3),
    high: a.range[1].toPrecision(3),
  };
}
