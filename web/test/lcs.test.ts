import { afterEach, describe, expect, it, vi } from "vitest";
import { LcsOverlay, curveRuns, legendLabels, magma, unresolvedNotes, vertexColors, type CurveAnswer, type FtleAnswer } from "../src/lcs";

// The overlay's colours are tvf ftle's (render/lcs_pictures.cpp's magma stops).
describe("magma", () => {
  it("runs from the first stop to the last, clamped outside [0, 1]", () => {
    expect(magma(0)).toEqual([0, 0, 4]);
    expect(magma(1)).toEqual([252, 253, 191]);
    expect(magma(-3)).toEqual([0, 0, 4]);
    expect(magma(7)).toEqual([252, 253, 191]);
    expect(magma(0.5)).toEqual([181, 54, 122]); // the middle stop of nine
  });
  it("interpolates linearly between stops, ever brighter", () => {
    expect(magma(1 / 16)).toEqual([14, 8, 36]); // half way from stop 0 to stop 1
    let last = -1;
    for (let i = 0; i <= 100; ++i) {
      const [r, g, b] = magma(i / 100);
      expect(r + g + b).toBeGreaterThanOrEqual(last); // monotone in brightness (the e2e test relies on it)
      last = r + g + b;
    }
  });
});

function answer(values: (number | null)[], range: [number, number], extra: Partial<FtleAnswer> = {}): FtleAnswer {
  return { revision: 1, t: 0, horizon: 1, direction: "forward", span: 1, cut: false, left: 0, min: null, max: null, range, values, seconds: 0, ...extra };
}

// The surface overlay's colours: one magma colour per vertex over the answer's range.
describe("vertexColors", () => {
  it("maps the range's ends to magma's ends and clamps beyond them", () => {
    const c = vertexColors(answer([1, 3, 2, 0, 9], [1, 3]));
    const rgb = (i: number) => Array.from(c.slice(3 * i, 3 * i + 3), (x) => Math.round(x * 255));
    expect(c.length).toBe(15);
    expect(rgb(0)).toEqual(magma(0));
    expect(rgb(1)).toEqual(magma(1));
    expect(rgb(2)).toEqual(magma(0.5));
    expect(rgb(3)).toEqual(magma(0)); // below the range
    expect(rgb(4)).toEqual(magma(1)); // above it
  });
  it("colours undefined values grey, and a flat field with the range's low end", () => {
    const c = vertexColors(answer([null, 2], [2, 2]));
    expect(Array.from(c.slice(0, 3), (x) => Math.round(x * 255))).toEqual([154, 154, 154]);
    expect(Array.from(c.slice(3, 6), (x) => Math.round(x * 255))).toEqual(magma(0));
  });
});

// Streaklines and timelines are cut where particles left the domain.
describe("curveRuns", () => {
  it("splits the points at the gaps, in order", () => {
    const points = [[0], [1], [2], [3], [4], [5]];
    expect(curveRuns({ points, gaps: [] })).toEqual([points]);
    expect(curveRuns({ points, gaps: [2, 5] })).toEqual([[[0], [1]], [[2], [3], [4]], [[5]]]);
    expect(curveRuns({ points: [], gaps: [] })).toEqual([]);
  });
});

describe("legendLabels", () => {
  it("names the direction, the horizon (cut where the window was shortened) and the range", () => {
    expect(legendLabels(answer([], [0.0123456, 2.5]))).toEqual({ title: "FTLE forward, T = 1", low: "0.0123", high: "2.50" });
    expect(legendLabels(answer([], [0, 1], { direction: "backward", horizon: 2, span: 0.75, cut: true })).title).toBe("FTLE backward, T = 0.750 (cut)");
  });
  it("says there is no FTLE where the window is empty, instead of a range", () => {
    expect(legendLabels(answer([null, null], [0, 1], { t: 20, span: 0, cut: true }))).toEqual({
      title: "FTLE forward: none at t = 20",
      low: "no time after it in the field's range",
      high: "",
    });
    expect(legendLabels(answer([null], [0, 1], { direction: "backward", span: 0 })).low).toBe("no time before it in the field's range");
  });
});

// The overlay against a server stub: what it keeps when the server refuses a seed, and when
// it takes a refusal back.
describe("LcsOverlay", () => {
  afterEach(() => vi.unstubAllGlobals());
  const curve = (x: number): CurveAnswer => ({
    revision: 1, t: 1, points: [[x, 0]], gaps: [], released: 1, left: 0, resolution: 1, largest_gap: 0, unresolved: 0,
    unresolved_by: null, seconds: 0.01,
  });
  // POST api/streakline answers per seed: x > 1 is outside the domain (422).
  function serve(ftleHorizonOk: (h: number) => boolean) {
    vi.stubGlobal("fetch", async (path: string, init: RequestInit) => {
      const reply = (status: number, body: unknown) => ({ ok: status < 300, status, json: async () => body });
      if (path.startsWith("api/ftle")) {
        const h = Number(new URLSearchParams(path.split("?")[1]).get("horizon"));
        return ftleHorizonOk(h) ? reply(200, answer([1, 2], [1, 2], { horizon: h })) : reply(400, { error: `ftle: "horizon" = ${h} is too short` });
      }
      const body = JSON.parse(init.body as string);
      if (path === "api/streakline")
        return body.seed[0] > 1 ? reply(422, { error: `streakline: the streakline seed (${body.seed[0]}, 0) is outside the domain` }) : reply(200, curve(body.seed[0]));
      return reply(200, curve(body.line[0][0]));
    });
  }
  it("drops a refused seed with its sentence and keeps drawing the others", async () => {
    serve(() => true);
    const errors: string[] = [], cleared: string[] = [];
    const lcs = new LcsOverlay(() => {}, (m) => errors.push(m), (m) => cleared.push(m));
    lcs.seeds = [[0.5, 0], [1.5, 0], [0.25, 0]];
    lcs.lines = [{ line: [[0, 0], [0.5, 0]], t: 0 }];
    await lcs.update(1, 0, undefined);
    expect(lcs.seeds).toEqual([[0.5, 0], [0.25, 0]]);
    expect(lcs.dye.map((d) => d.points[0][0])).toEqual([0.5, 0.25]);
    expect(lcs.timelines.length).toBe(1);
    expect(errors).toEqual(["streakline: the streakline seed (1.5, 0) is outside the domain"]);
    // The next update draws the kept ones and takes the sentence back.
    await lcs.update(0.5, 0, undefined);
    expect(lcs.dye.length).toBe(2);
    expect(cleared).toEqual(["streakline: the streakline seed (1.5, 0) is outside the domain"]);
  });
  it("takes back a refused horizon once a good one is drawn", async () => {
    serve((h) => h > 0.01);
    const errors: string[] = [], cleared: string[] = [];
    const lcs = new LcsOverlay(() => {}, (m) => errors.push(m), (m) => cleared.push(m));
    lcs.direction = "forward";
    lcs.horizon = 1e-9;
    await lcs.update(0, 0, undefined);
    expect(lcs.ftle).toBeUndefined();
    expect(errors).toEqual(['ftle: "horizon" = 1e-9 is too short']);
    lcs.horizon = 10;
    await lcs.update(0, 0, undefined);
    expect(lcs.ftle?.horizon).toBe(10);
    expect(cleared).toEqual(['ftle: "horizon" = 1e-9 is too short']);
  });
});

describe("unresolvedNotes", () => {
  const curve = (over: Partial<CurveAnswer> = {}): CurveAnswer => ({
    revision: 1,
    t: 2,
    points: [],
    gaps: [],
    released: 10,
    left: 0,
    resolution: 0.03125,
    largest_gap: 0.01,
    unresolved: 0,
    unresolved_by: null,
    seconds: 0,
    ...over,
  });
  it("says nothing when every curve is resolved", () => {
    expect(unresolvedNotes([curve()], [curve(), curve()])).toEqual([]);
  });
  it("names each unresolved curve, its gaps and why", () => {
    const notes = unresolvedNotes(
      [curve(), curve({ unresolved: 3, largest_gap: 0.5, unresolved_by: "particles" })],
      [curve({ t: 20, unresolved: 1, largest_gap: 0.0858, unresolved_by: "torn" })],
    );
    expect(notes).toEqual([
      "dye 2 at t = 2: 3 neighbours are further apart than 0.0313 (up to 0.5), drawn as straight lines; more than the server's 20,000 added releases are needed",
      "timeline 1 at t = 20: 1 neighbour is further apart than 0.0313 (up to 0.0858), drawn as straight lines; the flow tears it apart (particles within 1e-12 of each other on the line end up that far apart)",
    ]);
  });
});
