// The designer's latency, measured in the browser (issue 15): from the page's pointer
// event that places an element to the new picture (the page draws the new revision's
// field at its current frame: the result's frame, or, for the generators that solve frame
// by frame, that frame ready before the others: GET /api/preview), on the 65² × 100
// design that New starts, for each generator, with results pushed (GET /api/events) and
// with the polling fallback (the event stream refused), which is what the page did
// before. Beside it: the whole result held (every frame ready) and its analysis (paths,
// bifurcations, coherence: it follows the field). "server solve" is status.seconds, the
// whole solve; "the rest" is the picture's time minus it (negative when the picture came
// before the solve ended). Reported, not asserted (speed is never asserted in tests;
// docs/benchmarks.md keeps the numbers): the run fails only when a change does not reach
// the page. Writes latency.json and, after each generator's changes with pushed results,
// a screenshot latency_GENERATOR.png to --out.
// Usage: node e2e/latency.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH] [--changes N]
//        [--generators basis,spacetime] [--modes push] [--steps]
// --steps prints, for every change, the page's steps (window.tvf.marks) in ms after the event.
import fs from "node:fs";
import path from "node:path";
import { args, check, Designer, finish, launch, reportFailure, startServer, tempDir } from "./harness.mjs";

const a = args();
const n = Number(process.argv[process.argv.indexOf("--changes") + 1]) || 5;
const dir = tempDir("tvf-e2e-latency-");
const browser = await launch(a.chromium);
const server = await startServer(a.tvf, dir);
const only = process.argv.indexOf("--generators");
const generators = only > 0 ? process.argv[only + 1].split(",") : ["basis", "constrained", "spacetime", "deform"];
const median = (v) => [...v].sort((x, y) => x - y)[Math.floor(v.length / 2)];
const results = [];
let failed = false;
let page;
try {
  const modesAt = process.argv.indexOf("--modes");
  for (const mode of modesAt > 0 ? process.argv[modesAt + 1].split(",") : ["poll", "push"]) {
    const context = await browser.newContext({ viewport: { width: 1280, height: 860 } });
    page = await context.newPage();
    if (mode === "poll") await page.route("**/api/events", (route) => route.abort());
    await page.goto(server.url);
    const d = new Designer(page, server.url);
    await d.settled();
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
      const times = [];
      const analysed = [];
      const wholes = [];
      const solves = [];
      for (let k = 0; k < n; ++k) {
        const pixel = await d.at([-0.7 + (1.4 * k) / Math.max(1, n - 1), k % 2 ? 0.4 : -0.4]);
        const result = await page.evaluate(async ([x, y]) => {
          const c = document.getElementById("field");
          c.setPointerCapture = () => {}; // synthetic pointers cannot be captured
          const before = window.tvf.state.scene.revision;
          const o = { clientX: x, clientY: y, pointerId: 1, pointerType: "mouse", isPrimary: true, button: 0, bubbles: true };
          const t0 = performance.now();
          c.dispatchEvent(new PointerEvent("pointerdown", o));
          c.dispatchEvent(new PointerEvent("pointerup", o));
          // The new picture (the page draws the new revision's field at its frame: the
          // result's frame, or the shown frame of a solve under way), the whole result
          // (the page holds the new revision and its frame), then its analysis.
          let shown = -1;
          let whole = -1;
          for (const end = t0 + 60000; performance.now() < end; await new Promise((r) => setTimeout(r, 2))) {
            const s = window.tvf.state;
            if (shown < 0 && s.shownRevision > before) shown = performance.now() - t0;
            if (whole < 0 && s.resultRevision > before && s.frames.has(s.frame)) whole = performance.now() - t0;
            if (shown >= 0 && whole >= 0 && s.analysisRevision === s.resultRevision) {
              const steps = window.tvf.marks.filter(([, at]) => at >= t0).map(([what, at]) => `${what} @${Math.round(at - t0)}`);
              return [shown, whole, performance.now() - t0, steps];
            }
          }
          return [shown, whole, -1, []];
        }, pixel);
        const [ms, wholeMs, analysisMs, steps] = result;
        wholes.push(wholeMs);
        if (process.argv.includes("--steps")) console.log(`  ${mode} ${generator} change ${k + 1}: ${steps.join(", ")}`);
        analysed.push(analysisMs);
        check(ms >= 0, `${mode} · ${generator}: change ${k + 1} reached the page`);
        check(analysisMs >= 0, `${mode} · ${generator}: the analysis of change ${k + 1} reached the page`);
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
                    server_solve_median_ms: Math.round(median(solves)), beyond_solve_median_ms: Math.round(median(rest)) };
      results.push(row);
      console.log(`latency: ${mode.padEnd(4)} ${generator.padEnd(11)} median ${row.median_ms} ms (server solve ${row.server_solve_median_ms} ms, the rest ${row.beyond_solve_median_ms} ms) of ${times.map(Math.round).join(", ")}; whole result: median ${row.result_median_ms} ms; analysis shown: median ${row.analysis_median_ms} ms`);
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
