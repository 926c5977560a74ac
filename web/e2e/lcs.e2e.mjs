// The designer's LCS overlay and dye (issue 20) on the double gyre of example 22
// (Shadden, Lekien & Marsden 2005): the field is written as a native field file and held
// by key frames at every frame of a spacetime scene (so the designer shows exactly it).
// Turns FTLE forward on at t = 0 with T = 10 and checks in the picture that the repelling
// LCS, the brightest pixels of rows across x = 1, lie where tests/integrate/ftle_test.cpp
// finds it (x in [1.04, 1.36]); backward, the same turned by half a turn; then places a dye
// seed and checks the streakline is drawn and follows the time slider. The FTLE update
// time seen by the page is printed (never asserted).
// Usage: node e2e/lcs.e2e.mjs --tvf PATH/TO/tvf [--out DIR]
import fs from "node:fs";
import path from "node:path";
import { args, check, Designer, finish, launch, reportFailure, startServer, tempDir } from "./harness.mjs";

const a = args();
const dir = tempDir("tvf-lcs-");
const NX = 65;
const NY = 33;
const FRAMES = 41;
const T0 = 0;
const T1 = 20;

// The double gyre as a native field file (docs/file_formats.md; the layout of
// examples/22_double_gyre_ftle/make_double_gyre.py).
function writeGyre(file) {
  const A = 0.1;
  const EPS = 0.25;
  const W = (2 * Math.PI) / 10;
  const nv = NX * NY;
  const nf = 2 * (NX - 1) * (NY - 1);
  let header = JSON.stringify({ vertices: nv, faces: nf, frames: FRAMES, t0: T0, t1: T1, scene: null });
  header += " ".repeat((8 - ((20 + header.length) % 8)) % 8);
  const buf = Buffer.alloc(20 + header.length + nv * 24 + nf * 12 + FRAMES * nv * 16);
  let o = 0;
  o += buf.write("TVFFIELD", o, "latin1");
  o = buf.writeUInt32LE(1, o);
  o = buf.writeBigUInt64LE(BigInt(header.length), o);
  o += buf.write(header, o, "latin1");
  const xs = (i) => (2 * i) / (NX - 1);
  const ys = (i) => i / (NY - 1);
  for (let iy = 0; iy < NY; ++iy)
    for (let ix = 0; ix < NX; ++ix) {
      o = buf.writeDoubleLE(xs(ix), o);
      o = buf.writeDoubleLE(ys(iy), o);
      o = buf.writeDoubleLE(0, o);
    }
  for (let iy = 0; iy + 1 < NY; ++iy)
    for (let ix = 0; ix + 1 < NX; ++ix) {
      const v00 = iy * NX + ix;
      for (const v of [v00, v00 + 1, v00 + NX + 1, v00, v00 + NX + 1, v00 + NX]) o = buf.writeInt32LE(v, o);
    }
  for (let j = 0; j < FRAMES; ++j) {
    const t = T0 + ((T1 - T0) * j) / (FRAMES - 1);
    const aa = EPS * Math.sin(W * t);
    const b = 1 - 2 * aa;
    for (let iy = 0; iy < NY; ++iy)
      for (let ix = 0; ix < NX; ++ix) {
        const x = xs(ix);
        const y = ys(iy);
        const f = aa * x * x + b * x;
        o = buf.writeDoubleLE(-Math.PI * A * Math.sin(Math.PI * f) * Math.cos(Math.PI * y), o);
        o = buf.writeDoubleLE(Math.PI * A * Math.cos(Math.PI * f) * Math.sin(Math.PI * y) * (2 * aa * x + b), o);
      }
  }
  fs.writeFileSync(file, buf);
}

writeGyre(path.join(dir, "gyre.tvff"));
const times = Array.from({ length: FRAMES }, (_, j) => T0 + ((T1 - T0) * j) / (FRAMES - 1));
fs.writeFileSync(
  path.join(dir, "scene.json"),
  JSON.stringify({
    tvf: 1,
    description: "The double gyre (example 22) held by key frames at every frame",
    domain: { grid: { size: [NX, NY], min: [0, 0], max: [2, 1] } },
    time: { frames: FRAMES, range: [T0, T1] },
    generator: "spacetime",
    keyframes: times.map((t) => ({ t, field: "gyre.tvff" })),
  }),
);

const browser = await launch(a.chromium);
const server = await startServer(a.tvf, dir);
let failed = false;
let page;
try {
  page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  const d = await Designer.open(page, server.url, 120000);
  await d.goto(0);
  await d.settled();

  // The brightness (R + G + B; magma's is monotone) of the canvas at world points.
  const brightness = (points) =>
    page.evaluate((pts) => {
      const c = document.getElementById("field");
      const g = c.getContext("2d");
      const v = window.tvf.view();
      return pts.map((p) => {
        const [x, y] = v.toCanvas(p);
        const px = g.getImageData(Math.round(x), Math.round(y), 1, 1).data;
        return px[0] + px[1] + px[2];
      });
    }, points);
  // The x of the brightest pixel of the row y within [0.6, 1.4].
  const ridge = async (y) => {
    const xs = Array.from({ length: 81 }, (_, i) => 0.6 + 0.01 * i);
    const b = await brightness(xs.map((x) => [x, y]));
    let best = 0;
    for (let i = 1; i < b.length; ++i) if (b[i] > b[best]) best = i;
    return { x: xs[best], peak: b[best], median: [...b].sort((p, q) => p - q)[40] };
  };
  const waitFtle = async (direction, t) => {
    await page.waitForFunction(
      ([dir, time]) => {
        const f = window.tvf.lcs.ftle;
        return f && f.direction === dir && Math.abs(f.t - time) < 1e-9;
      },
      [direction, t],
      { timeout: 60000 },
    );
    return page.evaluate(() => ({ ms: window.tvf.lcs.lastUpdateMs, seconds: window.tvf.lcs.ftle.seconds, range: window.tvf.lcs.ftle.range }));
  };

  // FTLE forward, T = 10, at t = 0.
  await page.fill("#lcs-horizon", "10");
  await page.dispatchEvent("#lcs-horizon", "change");
  const started = Date.now();
  await page.selectOption("#lcs-mode", "forward");
  const fw = await waitFtle("forward", 0);
  console.log(
    `FTLE forward at t = 0, T = 10 on ${NX} × ${NY}: ${fw.ms.toFixed(0)} ms from request to picture in the page ` +
      `(${(fw.seconds * 1000).toFixed(0)} ms computing on the server; ${Date.now() - started} ms script time), range ${fw.range.map((v) => v.toFixed(3))}`,
  );
  await d.shot(a.out, "lcs_ftle_forward_t0.png");
  for (const y of [0.1, 0.2, 0.3, 0.4, 0.6, 0.7]) {
    const r = await ridge(y);
    check(r.x >= 1.04 && r.x <= 1.36 && r.peak > 1.5 * r.median, `forward ridge in row y = ${y} at x = ${r.x.toFixed(2)} (brightness ${r.peak} vs median ${r.median})`);
  }
  // Backward at t = 10 (over [0, 10]; the field has period 10, so this is the backward
  // FTLE at t = 0): the attracting LCS, the forward one turned by half a turn (2 − x, 1 − y),
  // since V(2 − x, 1 − y, −t) = V(x, y, t).
  await page.selectOption("#lcs-mode", "backward");
  await d.goto(20);
  const bw = await waitFtle("backward", 10);
  console.log(`FTLE backward at t = 10: ${bw.ms.toFixed(0)} ms from request to picture (${(bw.seconds * 1000).toFixed(0)} ms on the server)`);
  await d.shot(a.out, "lcs_ftle_backward_t10.png");
  for (const y of [0.3, 0.4, 0.6, 0.8, 0.9]) {
    const xs = Array.from({ length: 81 }, (_, i) => 0.6 + 0.01 * i);
    const b = await brightness(xs.map((x) => [x, y]));
    let best = 0;
    for (let i = 1; i < b.length; ++i) if (b[i] > b[best]) best = i;
    const x = xs[best];
    check(2 - x >= 1.04 && 2 - x <= 1.36, `backward ridge in row y = ${y} at x = ${x.toFixed(2)} (mirror of the forward one)`);
  }

  // Scrubbing updates the overlay: at t = 5 the picture is of t = 5.
  await d.goto(10);
  const later = await waitFtle("backward", 5);
  console.log(`FTLE backward at t = 5 after moving the slider: ${later.ms.toFixed(0)} ms`);

  // Dye: a seed at (1.0, 0.3); at t = 10 the streakline released since t = 0.
  await page.selectOption("#lcs-mode", "off");
  await d.goto(20);
  await d.settled();
  await page.waitForFunction(() => !window.tvf.lcs.ftle);
  await d.tool("dye");
  await d.click([1.0, 0.3]);
  await page.waitForFunction(() => window.tvf.lcs.dye.length === 1 && Math.abs(window.tvf.lcs.dye[0].t - 10) < 1e-9, null, { timeout: 60000 });
  const dye10 = await page.evaluate(() => window.tvf.lcs.dye[0]);
  check(dye10.points.length > 50, `the streakline at t = 10 has ${dye10.points.length} points (${dye10.released} released, ${dye10.left} left)`);
  const newest = dye10.points[dye10.points.length - 1];
  check(Math.hypot(newest[0] - 1.0, newest[1] - 0.3) < 1e-6, "its newest point is at the seed");
  let spread = 0;
  for (const p of dye10.points) spread = Math.max(spread, Math.hypot(p[0] - 1.0, p[1] - 0.3));
  check(spread > 0.3, `the dye has been carried away from the seed (up to ${spread.toFixed(2)})`);
  // Drawn: green pixels (the dye colour) at the middle of the line.
  const green = await page.evaluate((pts) => {
    const c = document.getElementById("field");
    const g = c.getContext("2d");
    const v = window.tvf.view();
    let n = 0;
    for (const p of pts) {
      const [x, y] = v.toCanvas(p);
      const px = g.getImageData(Math.round(x), Math.round(y), 1, 1).data;
      if (px[1] > 120 && px[0] < 80 && px[2] < 120) ++n;
    }
    return n;
  }, dye10.points.filter((_, i) => i % 5 === 0));
  const sampled = Math.ceil(dye10.points.length / 5);
  check(green >= 0.6 * sampled, `the streakline is drawn (${green} of ${sampled} sampled points dye-green)`);
  await d.shot(a.out, "lcs_dye_t10.png");
  // Moving the slider back to t = 5: a shorter streak, of t = 5.
  await d.goto(10);
  await page.waitForFunction(() => Math.abs(window.tvf.lcs.dye[0]?.t - 5) < 1e-9, null, { timeout: 60000 });
  const dye5 = await page.evaluate(() => window.tvf.lcs.dye[0]);
  check(dye5.points.length < dye10.points.length, `at t = 5 the streak is younger (${dye5.points.length} points)`);
  // A seed above the domain (in the white margin): refused with the server's sentence, and
  // dropped; the good streakline stays drawn, and once the time moves the sentence goes.
  await d.click([1.0, 1.3]);
  await page.waitForFunction(() => document.getElementById("message").textContent.includes("outside the domain"), null, { timeout: 60000 });
  const afterBad = await page.evaluate(() => ({ seeds: window.tvf.lcs.seeds.length, dye: window.tvf.lcs.dye.length }));
  check(afterBad.seeds === 1 && afterBad.dye === 1, `a seed outside the domain is refused and dropped, the other kept (${afterBad.seeds} seed, ${afterBad.dye} streakline)`);
  await d.goto(12);
  await page.waitForFunction(() => Math.abs(window.tvf.lcs.dye[0]?.t - 6) < 1e-9, null, { timeout: 60000 });
  const said = await page.evaluate(() => document.getElementById("message").textContent);
  check(!said.includes("outside the domain"), `the refusal leaves the status line once the dye is drawn again ("${said}")`);
  await d.goto(10);
  await page.waitForFunction(() => Math.abs(window.tvf.lcs.dye[0]?.t - 5) < 1e-9, null, { timeout: 60000 });
  // A timeline: the segment y = 0.5 dragged at t = 5, then seen at t = 10, wound round
  // the gyres and refined where it stretches.
  await page.selectOption("#lcs-mode", "off");
  await d.drag([
    [0.1, 0.5],
    [1.9, 0.5],
  ]);
  await page.waitForFunction(() => window.tvf.lcs.timelines.length === 1, null, { timeout: 60000 });
  const drawn = await page.evaluate(() => window.tvf.lcs.timelines[0]);
  check(drawn.points.every((p) => Math.abs(p[1] - 0.5) < 0.02), `at the time it is drawn the timeline is the segment (${drawn.points.length} points)`);
  await d.goto(20);
  await page.waitForFunction(() => Math.abs(window.tvf.lcs.timelines[0]?.t - 10) < 1e-9, null, { timeout: 60000 });
  const carried = await page.evaluate(() => window.tvf.lcs.timelines[0]);
  const ys = carried.points.map((p) => p[1]);
  check(carried.points.length > drawn.points.length && Math.max(...ys) - Math.min(...ys) > 0.3,
    `five time units later it is carried and stretched (${carried.points.length} points, y over ${Math.min(...ys).toFixed(2)}–${Math.max(...ys).toFixed(2)})`);
  await d.shot(a.out, "lcs_timeline_t10.png");
  // Resolved (the server's answers say so): no note under the view.
  check(carried.unresolved === 0 && carried.unresolved_by === null && (await page.isHidden("#lcs-notes")),
    `the resolved timeline is not noted (largest gap ${carried.largest_gap.toFixed(3)}, resolution ${carried.resolution.toFixed(3)})`);
  // An answer with neighbours left apart (the server's own, with its resolution keys set as
  // a torn line's are: no designed field on this grid tears one at 1e-12) is said under the
  // view, with what stopped it; the next resolved answer takes the note away.
  await page.route("**/api/timeline", async (route) => {
    const response = await route.fetch();
    const json = await response.json();
    Object.assign(json, { unresolved: 2, largest_gap: 0.25, unresolved_by: "torn" });
    await route.fulfill({ response, json });
  });
  await d.goto(19);
  await page.waitForSelector("#lcs-notes:not([hidden])", { timeout: 60000 });
  const note = await page.textContent("#lcs-notes");
  check(/^note: timeline 1 at t = 9\.5\d*: 2 neighbours are further apart than [\d.]+ \(up to 0\.25\), drawn as straight lines; the flow tears it apart/.test(note),
    `an unresolved timeline is noted: ${note}`);
  await d.shot(a.out, "lcs_timeline_note.png");
  await page.unroute("**/api/timeline");
  await d.goto(20);
  await page.waitForSelector("#lcs-notes[hidden]", { state: "attached", timeout: 60000 });
  await d.goto(10);
  // With the FTLE under it.
  await page.selectOption("#lcs-mode", "forward");
  await waitFtle("forward", 5);
  await d.shot(a.out, "lcs_dye_ftle_t5.png");
  // A bad horizon is refused with one sentence.
  const bad = await page.evaluate(() => fetch("api/ftle?t=0&horizon=-1").then(async (r) => [r.status, (await r.json()).error]));
  check(bad[0] === 400 && /horizon/.test(bad[1]), `a negative horizon is refused: ${bad[1]}`);
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, `${a.out}/lcs_failure.png`);
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
