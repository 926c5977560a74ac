// The designer's latency, measured in the browser (issue 15): from the page's pointer
// event that places an element to the new picture (the page draws the new revision's
// field at its current frame: the result's frame, or, for the generators that solve frame
// by frame, that frame ready before the others: GET /api/preview), on the 65² × 100
// design that New starts, for each generator, with results pushed (GET /api/events) and
// with the polling fallback (the event stream refused), which is what the page did
// before; then, pushed only, on the 20,252-vertex geodesic sphere × 100 frames (the
// benchmarks' sphere, written here as an OFF file; sources clicked on the surface, or for
// `deform` a vortex turned, as on the grid). Each
// change adds a source, except for `deform`, which ignores the scene's elements (the page
// refuses them, checked here): its changes turn the whole field by a new angle. Beside it: the whole result held (every frame ready) and its analysis (paths,
// bifurcations, coherence: it follows the field). "server solve" is status.seconds, the
// whole solve; "the rest" is the picture's time minus it (negative when the picture came
// before the solve ended). Reported, not asserted (speed is never asserted in tests;
// docs/benchmarks.md keeps the numbers): the run fails only when a change does not reach
// the page. Writes latency.json and, after each generator's changes with pushed results,
// a screenshot latency_GENERATOR.png to --out.
// Usage: node e2e/latency.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH] [--changes N]
//        [--generators basis,spacetime] [--modes push] [--sphere basis,constrained,spacetime,deform|none]
//        [--sphere-changes N] [--steps]
//        [--serve "--solve-while-saving ..."] (more options for tvf serve, space-separated)
// --steps prints, for every change, the page's steps (window.tvf.marks) in ms after the event.
// --no-analysis-wait makes each change as soon as the last one's picture and whole result are
// there, as a designer clicking on does, without waiting for its analysis (only the last
// change's analysis is waited for): the analysis of a replaced field then meets the next
// change's solve. It also reports "server CPU": the server process's CPU time (all its
// threads, /proc/PID/stat, 10 ms ticks) from the event to the whole result, median over
// the changes but the last.
import fs from "node:fs";
import path from "node:path";
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-latency-");
const n = Number(process.argv[process.argv.indexOf("--changes") + 1]) || 5;
const only = process.argv.indexOf("--generators");
const generators = only > 0 ? process.argv[only + 1].split(",") : ["basis", "constrained", "spacetime", "deform"];
const sphereAt = process.argv.indexOf("--sphere");
const sphereGenerators = sphereAt > 0 ? process.argv[sphereAt + 1].split(",").filter((g) => g !== "none")
                                       : ["basis", "constrained", "spacetime", "deform"];
// Changes on the sphere (each one a whole 20k × 100 field and its analysis: seconds idle,
// a minute or more on a loaded machine), and how long one may take to reach the page.
const sphereChangesAt = process.argv.indexOf("--sphere-changes");
const sphereChanges = sphereChangesAt > 0 ? Number(process.argv[sphereChangesAt + 1]) : n;
const median = (v) => [...v].sort((x, y) => x - y)[Math.floor(v.length / 2)];
const noAnalysisWait = process.argv.includes("--no-analysis-wait");
// The server's CPU time so far in ms (user + system, all threads; Linux).
const serverCpuMs = () => {
  try {
    const f = fs.readFileSync(`/proc/${server.proc.pid}/stat`, "utf8").split(") ")[1].split(" ");
    return (Number(f[11]) + Number(f[12])) * 10;  // utime, stime (fields 14, 15) in 1/100 s
  } catch {
    return NaN;
  }
};

// The geodesic sphere of the benchmarks (make_geodesic_sphere(45): each icosahedron face
// cut into 45² triangles, projected on the unit sphere; 10·45² + 2 = 20,252 vertices) as OFF.
function geodesicSphereOff(n) {
  const t = (1 + Math.sqrt(5)) / 2;
  const ico = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]];
  const faces = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
                 [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]];
  const unit = (p) => { const r = Math.hypot(...p); return p.map((x) => x / r); };
  const vertices = [];
  const index = new Map();
  const vertex = (p) => {
    const q = unit(p);
    const key = q.map((x) => Math.round(x * 1e6)).join(",");
    if (!index.has(key)) { index.set(key, vertices.length); vertices.push(q); }
    return index.get(key);
  };
  const tris = [];
  for (const [a, b, c] of faces) {
    const [A, B, C] = [ico[a], ico[b], ico[c]];
    const at = (i, j) => vertex([0, 1, 2].map((k) => A[k] + ((B[k] - A[k]) * i) / n + ((C[k] - A[k]) * j) / n));
    for (let i = 0; i < n; ++i)
      for (let j = 0; i + j < n; ++j) {
        tris.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
        if (i + j < n - 1) tris.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
      }
  }
  // Outward normals (counter-clockwise seen from outside).
  for (const f of tris) {
    const [p, q, r] = f.map((v) => vertices[v]);
    const u = [0, 1, 2].map((k) => q[k] - p[k]);
    const w = [0, 1, 2].map((k) => r[k] - p[k]);
    const nrm = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
    if (nrm[0] * (p[0] + q[0] + r[0]) + nrm[1] * (p[1] + q[1] + r[1]) + nrm[2] * (p[2] + q[2] + r[2]) < 0) [f[1], f[2]] = [f[2], f[1]];
  }
  return `OFF\n${vertices.length} ${tris.length} 0\n${vertices.map((v) => v.map((x) => x.toFixed(9)).join(" ")).join("\n")}\n${tris.map((f) => `3 ${f.join(" ")}`).join("\n")}\n`;
}

// One change, timed in the page from its event: `act` is {pointer: [clientX, clientY],
// selector} (a click there: pointerdown, pointerup) or {turn: θ} (the Rotate field button
// with that angle); with `noAnalysis` it returns once the picture and the whole result are
// there (analysis shown: null). Returns [picture, whole result, analysis shown, steps] in
// ms (−1: not reached within a minute).
const timeChange = (page, act) =>
  page.evaluate(async (act) => {
    const before = window.tvf.state.scene.revision;
    const t0 = performance.now();
    if (act.pointer) {
      const c = document.querySelector(act.selector);
      c.setPointerCapture = () => {}; // synthetic pointers cannot be captured
      const [x, y] = act.pointer;
      const o = { clientX: x, clientY: y, pointerId: 1, pointerType: "mouse", isPrimary: true, button: 0, bubbles: true };
      c.dispatchEvent(new PointerEvent("pointerdown", o));
      c.dispatchEvent(new PointerEvent("pointerup", o));
    } else {
      document.getElementById("field-turn").value = String(act.turn);
      document.getElementById("rotate-field").click();
    }
    // The new picture (the page draws the new revision's field at its frame: the
    // result's frame, or the shown frame of a solve under way), the whole result (the
    // page holds the new revision and its frame), then its analysis.
    let shown = -1;
    let whole = -1;
    for (const end = t0 + (act.waitMs ?? 60000); performance.now() < end; await new Promise((r) => setTimeout(r, 2))) {
      const s = window.tvf.state;
      if (shown < 0 && s.shownRevision > before) shown = performance.now() - t0;
      if (whole < 0 && s.resultRevision > before && s.frames.has(s.frame)) whole = performance.now() - t0;
      if (shown >= 0 && whole >= 0 && (act.noAnalysis || s.analysisRevision === s.resultRevision)) {
        const steps = window.tvf.marks.filter(([, at]) => at >= t0).map(([what, at]) => `${what} @${Math.round(at - t0)}`);
        return [shown, whole, act.noAnalysis ? null : performance.now() - t0, steps];
      }
    }
    // Not there: what the page was doing (printed with the failure).
    const s = window.tvf.state;
    const steps = window.tvf.marks.filter(([, at]) => at >= t0).map(([what, at]) => `${what} @${Math.round(at - t0)}`);
    steps.push(`page: result ${s.resultRevision}, analysis ${s.analysisRevision}, frame ${s.frame} ${s.frames.has(s.frame) ? "loaded" : "missing"}, ` +
      `status handling ${JSON.stringify(window.tvf.pending())}`);
    return [shown, whole, -1, steps];
  }, act);
const results = [];
let failed = false;
let page;

// `n` changes made by `actFor(k)` (timeChange's act), timed; prints and records a row.
async function series(page, d, mode, generator, actFor, count = n) {
  const times = [];
  const analysed = [];
  const wholes = [];
  const solves = [];
  const cpus = [];
  for (let k = 0; k < count; ++k) {
    const act = await actFor(k);
    act.noAnalysis = noAnalysisWait && k + 1 < count;
    const cpu0 = serverCpuMs();
    const result = await timeChange(page, act);
    if (act.noAnalysis) cpus.push(serverCpuMs() - cpu0);
    const [ms, wholeMs, analysisMs, steps] = result;
    wholes.push(wholeMs);
    if (process.argv.includes("--steps")) console.log(`  ${mode} ${generator} change ${k + 1}: ${steps.join(", ")}`);
    check(ms >= 0, `${mode} · ${generator}: change ${k + 1} reached the page`);
    if (analysisMs !== null) {
      analysed.push(analysisMs);
      if (analysisMs < 0) console.log(`  the page's steps: ${steps.join(", ")}`);
      check(analysisMs >= 0, `${mode} · ${generator}: the analysis of change ${k + 1} reached the page`);
    }
    times.push(ms);
    solves.push(1000 * ((await d.status()).seconds ?? 0));
  }
  // The designer after the changes (to look at): latency_GENERATOR.png in --out.
  if (mode === "push") {
    fs.mkdirSync(a.out, { recursive: true });
    await page.screenshot({ path: path.join(a.out, `latency_${generator}.png`) });
  }
  const rest = times.map((t, k) => t - solves[k]);
  const row = { mode, generator, change_to_ready_ms: times.map(Math.round), median_ms: Math.round(median(times)),
                change_to_result_ms: wholes.map(Math.round), result_median_ms: Math.round(median(wholes)),
                change_to_analysis_ms: analysed.map(Math.round), analysis_median_ms: Math.round(median(analysed)),
                server_solve_median_ms: Math.round(median(solves)), beyond_solve_median_ms: Math.round(median(rest)),
                server_cpu_ms: cpus, server_cpu_median_ms: cpus.length ? median(cpus) : null };
  results.push(row);
  console.log(`latency: ${mode.padEnd(4)} ${generator.padEnd(17)} median ${row.median_ms} ms (server solve ${row.server_solve_median_ms} ms, the rest ${row.beyond_solve_median_ms} ms) of ${times.map(Math.round).join(", ")}; whole result: median ${row.result_median_ms} ms; analysis shown: median ${row.analysis_median_ms} ms` +
              (cpus.length ? `; server CPU to the whole result: median ${row.server_cpu_median_ms} ms of ${cpus.join(", ")}` : ""));
}

try {
  const modesAt = process.argv.indexOf("--modes");
  for (const mode of modesAt > 0 ? process.argv[modesAt + 1].split(",") : ["poll", "push"]) {
    const context = await browser.newContext({ viewport: { width: 1280, height: 860 } });
    page = await context.newPage();
    if (mode === "poll") await page.route("**/api/events", (route) => route.abort());
    const d = await Designer.open(page, server.url);
    for (const generator of generators) {
      await d.change(() => page.click("#new"));
      if (generator === "deform") {
        // The deform generator needs a base design: a vortex, then the whole field turned.
        await d.tool("singular");
        await page.uncheck("#keyframe-mode");
        await page.selectOption("#singular-type", "ccw_center");
        await d.change(() => d.click([0, 0]));
        await page.fill("#field-turn", "0.5");
        await d.change(() => page.click("#rotate-field"));
      } else if ((await d.scene()).scene.generator !== generator) {
        await d.change(() => page.selectOption("#generator", generator));
      }
      check((await d.scene()).scene.generator === generator, `${mode}: the design uses the ${generator} generator`);
      await d.tool("singular");
      await page.uncheck("#keyframe-mode");
      await page.selectOption("#singular-type", "source");
      if (generator === "deform") {
        // A source clicked now would go into the scene's elements, which the deform
        // generator ignores: the page says so and adds nothing.
        const before = (await d.scene()).scene;
        await d.click([0.3, 0.3]);
        await page.waitForTimeout(300);
        const after = await d.scene();
        check(after.revision === (await d.status()).revision && JSON.stringify(after.scene) === JSON.stringify(before) &&
              /deform generator ignores/.test(await page.textContent("#message")),
              `${mode}: a source clicked with the deform generator is not added, and the page says why`);
      }
      await series(page, d, mode, generator, async (k) =>
        generator === "deform"
          ? { turn: 0.5 + 0.25 * (k + 1) }
          : { pointer: await d.at([-0.7 + (1.4 * k) / Math.max(1, n - 1), k % 2 ? 0.4 : -0.4]), selector: "#field" });
    }
    if (mode === "push" && sphereGenerators.length) {
      // The 20,252-vertex sphere × 100 frames: a vortex, then sources clicked on the side
      // the camera sees (it looks from (0.2, −1, 0.6)).
      fs.writeFileSync(path.join(dir, "sphere20k.off"), geodesicSphereOff(45));
      for (const generator of sphereGenerators) {
        const vortex = { kind: "singular", type: "ccw_center", path: [[0.0, -0.8, 0.6, 0]] };
        const scene = { tvf: 1, domain: { mesh: "sphere20k.off" }, time: { frames: 100, range: [0, 1] }, generator,
                        elements: [vortex] };
        if (generator === "deform") {
          // As on the grid: the vortex is the base design, and each change turns the field.
          scene.elements = [];
          scene.deform = { base: { elements: [vortex] },
                           transform: [{ t: 0, sx: 1, sy: 1, theta: 0 }, { t: 1, sx: 1, sy: 1, theta: 0.5 }] };
        }
        await d.applyScene(scene, 300000);
        await d.tool("singular");
        await page.uncheck("#keyframe-mode");
        await page.selectOption("#singular-type", "source");
        const sb = await page.locator("#surface canvas").boundingBox();
        await series(page, d, mode, `sphere20k_${generator}`, async (k) => {
          if (generator === "deform") return { turn: 0.5 + 0.25 * (k + 1), waitMs: 300000 };
          const q = [-0.6 + (1.2 * k) / Math.max(1, sphereChanges - 1), -1, k % 2 ? 0.5 : 0.1];
          const r = Math.hypot(...q);
          const [x, y] = await page.evaluate((p) => window.tvf.surface(p), q.map((v) => v / r));
          return { pointer: [sb.x + x, sb.y + y], selector: "#surface canvas", waitMs: 300000 };
        }, sphereChanges);
      }
    }
    await context.close();
  }
  fs.mkdirSync(a.out, { recursive: true });
  fs.writeFileSync(path.join(a.out, "latency.json"), JSON.stringify(results, null, 1));
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, path.join(a.out, "latency_failure.png"));
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
