// End-to-end test of the periodic orbits in the designer's views (issue 20): the cycles
// the analysis finds at the shown frame are drawn over the field, attracting orange and
// repelling teal (web/src/orbits.ts), on the plane (example 23's two Hopf templates on a
// 33² grid) and on a surface (a supercritical Hopf template on a sphere, spacetime
// generator) as tubes on the mesh. Checked: at a frame with a cycle, the loop's points are
// that colour in the picture (the plane's canvas; on the sphere the points the camera
// sees); at a frame without one, no point is. Screenshots of both (looked at by people).
// Usage: node e2e/orbits.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import fs from "node:fs";
import path from "node:path";
import { args, check, Designer, launch, reportFailure, startServer, stopServer, tempDir } from "./harness.mjs";

const a = args();
const ORANGE = [0xee, 0x80, 0x0d];
const TEAL = [0x00, 0x99, 0x99];
const near = (c, want, tol = 40) => c.every((x, k) => Math.abs(x - want[k]) <= tol);

// The colours of a view's picture at world points (after the next animation frame).
function colours(page, which, points) {
  return page.evaluate(
    async ([w, pts]) => {
      await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
      const { data, width, scale } = window.tvf.pixels(w);
      return pts.map((p) => {
        const [x, y] = (w === "surface" ? window.tvf.surface(p) : window.tvf.view().toCanvas(p)).map((v) => Math.round(v * scale));
        return Array.from(data.slice(4 * (y * width + x), 4 * (y * width + x) + 3));
      });
    },
    [which, points],
  );
}

async function orbitsOf(page, frame) {
  return page.evaluate((j) => (window.tvf.state.analysis?.periodic_orbits ?? []).filter((o) => o.frame === j), frame);
}

async function scenario(browser, name, scene, frames, which) {
  const dir = tempDir(`tvf-orbits-${name}-`);
  fs.writeFileSync(path.join(dir, "scene.json"), JSON.stringify(scene));
  const server = await startServer(a.tvf, dir);
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  try {
    const d = await Designer.open(page, server.url, 240000);
    await d.settled(240000);
    await page.waitForFunction(() => window.tvf.state.analysis?.periodic_orbits !== undefined, null, { timeout: 240000 });
    const [withCycle, without] = frames;
    await d.goto(withCycle);
    await d.settled(240000);
    const orbits = await orbitsOf(page, withCycle);
    check(orbits.length >= 1, `${name}: the analysis has ${orbits.length} cycle(s) at frame ${withCycle}`);
    for (const o of orbits) {
      const want = o.stability === "attracting" ? ORANGE : TEAL;
      let pts = o.points.filter((_, i) => i % 3 === 0);
      if (which === "surface") {
        const seen = await page.evaluate((ps) => ps.map((p) => window.tvf.surfaceVisible(p)), pts);
        pts = pts.filter((_, i) => seen[i]);
      }
      const c = await colours(page, which, pts);
      const hits = c.filter((x) => near(x, want)).length;
      check(pts.length >= 5 && hits >= 0.6 * pts.length,
        `${name}: the ${o.stability} cycle of radius ${o.radius.toFixed(3)} at t = ${o.t.toFixed(3)} is drawn (${hits} of ${pts.length} sampled points its colour)`);
    }
    await d.shot(a.out, `orbits_${name}.png`);
    // A frame without cycles: none of the loops' colours where the other frame's loop was.
    await d.goto(without);
    await d.settled(240000);
    check((await orbitsOf(page, without)).length === 0, `${name}: no cycle at frame ${without}`);
    if (orbits.length) {
      let pts = orbits[0].points.filter((_, i) => i % 3 === 0);
      if (which === "surface") {
        const seen = await page.evaluate((ps) => ps.map((p) => window.tvf.surfaceVisible(p)), pts);
        pts = pts.filter((_, i) => seen[i]);
      }
      const c = await colours(page, which, pts);
      const hits = c.filter((x) => near(x, ORANGE, 25) || near(x, TEAL, 25)).length;
      check(hits <= 0.1 * pts.length, `${name}: at frame ${without} the loop is gone (${hits} of ${pts.length} points in a cycle's colour)`);
    }
  } catch (e) {
    await reportFailure(e, page, server, `${a.out}/orbits_${name}_failure.png`);
    throw e;
  } finally {
    await page.close();
    await stopServer(server);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

const browser = await launch(a.chromium);
let failed = false;
try {
  // Example 23's supercritical template on 33² × 41 frames, at (−0.5, 0), t = 0.35 (with
  // the subcritical one too a cycle lives at every time): frame 36 (t = 0.9) holds its
  // attracting cycle, frame 8 (t = 0.2) none.
  await scenario(browser, "plane", {
    tvf: 1,
    domain: { grid: { size: [33, 33], min: [-1, -1], max: [1, 1] } },
    time: { frames: 41, range: [0, 1] },
    generator: "basis",
    falloff: 150,
    elements: [
      { kind: "bifurcation", type: "hopf_supercritical", at: [-0.5, 0.0, 0.35], scale: 0.3, time_scale: 0.4, angle: 0 },
    ],
  }, [36, 8], "field");
  // A sphere (4 subdivisions) with a supercritical template facing the default camera,
  // spacetime: its attracting cycle from t = 0.5 on.
  await scenario(browser, "sphere", {
    tvf: 1,
    domain: { sphere: { subdivisions: 4, radius: 1 } },
    time: { frames: 21, range: [0, 1] },
    generator: "spacetime",
    elements: [
      { kind: "bifurcation", type: "hopf_supercritical", at: [0.8, -0.48, 0.36, 0.3], scale: 0.45, time_scale: 0.4, angle: 0 },
    ],
  }, [18, 2], "surface");
} catch {
  failed = true;  // reported by the scenario
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
