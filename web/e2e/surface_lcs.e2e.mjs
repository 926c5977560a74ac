// End-to-end test of the designer's LCS overlay, Dye tool and Streakline tool on surfaces
// (issue 20). On the sphere (a source, a saddle and a moving sink, basis generator):
// - FTLE forward on: the mesh takes each vertex's magma colour. The page's answer is
//   /api/ftle's (values and colour range, which the legend shows); the legend is drawn
//   over the view's corner, dark to bright; over the vertices the camera sees, the
//   picture's brightness follows σ (rank correlation) and spans dark to bright; turned
//   off, the mesh is the grey moving texture again;
// - a Dye click on the sphere: the streakline released there since the first time comes
//   back at the current time, its newest point at the click, every point on the mesh
//   (distance to the nearest face), carried away from the seed, drawn in dye green where
//   the camera sees it, and younger when the slider goes back; a Dye drag: a timeline,
//   on the mesh, the shortest path over it between the drag's ends at the time it was
//   drawn (within 0.05 of the chord), carried later;
// - the Streakline tool: an S dragged on the sphere at t = 0.8 becomes a streakline
//   element of [x, y, z] points, and the dye traced in the new field (POST
//   /api/streakline) lies on the sketch (Hausdorff distance within 1.5 mean edge lengths).
// On the Stanford bunny (examples/04_surface_mesh, when its bunny.off is there): the FTLE
// overlay and dye (a few seeds and a timeline), with the same checks of the colours and of
// the dye on the mesh; screenshots of both (looked at by people, not compared). --no-bunny
// leaves the bunny out (the sanitizer build does: its FTLE takes minutes there).
// Usage: node e2e/surface_lcs.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH] [--no-bunny]
import fs from "node:fs";
import path from "node:path";
import { args, check, Designer, finish, launch, reportFailure, startServer, stopServer, tempDir } from "./harness.mjs";

const a = args();
const bunny = path.resolve("../examples/04_surface_mesh");
const norm = (v) => Math.hypot(...v);
const unit = (v) => v.map((x) => x / norm(v));
const sub = (u, v) => u.map((x, k) => x - v[k]);
const dot = (u, v) => u.reduce((s, x, k) => s + x * v[k], 0);
const dist = (u, v) => norm(sub(u, v));
// Magma's stops (web/src/lcs.ts): the legend's ends.
const MAGMA_LO = [0, 0, 4];
const MAGMA_HI = [252, 253, 191];

// The distance from p to the triangle abc (closest point, Ericson's Real-Time Collision
// Detection §5.1.5).
function triangleDistance(p, a, b, c) {
  const ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return dist(p, a);
  const bp = sub(p, b), d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist(p, b);
  const vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return dist(p, a.map((x, k) => x + (d1 / (d1 - d3)) * ab[k]));
  const cp = sub(p, c), d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist(p, c);
  const vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return dist(p, a.map((x, k) => x + (d2 / (d2 - d6)) * ac[k]));
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const w = (d4 - d3) / (d4 - d3 + (d5 - d6));
    return dist(p, b.map((x, k) => x + w * (c[k] - x)));
  }
  const den = 1 / (va + vb + vc);
  const v = vb * den, w = vc * den;
  return dist(p, a.map((x, k) => x + v * ab[k] + w * ac[k]));
}
// The largest distance from the points to the mesh (faces near each point only: those
// with a corner within `near`).
function offMesh(mesh, points, near) {
  const V = (i) => [mesh.vertices[3 * i], mesh.vertices[3 * i + 1], mesh.vertices[3 * i + 2]];
  let worst = 0;
  for (const p of points) {
    let best = Infinity;
    for (let f = 0; f < mesh.faces.length; f += 3) {
      const [x, y, z] = [V(mesh.faces[f]), V(mesh.faces[f + 1]), V(mesh.faces[f + 2])];
      if (dist(p, x) > near && dist(p, y) > near && dist(p, z) > near) continue;
      best = Math.min(best, triangleDistance(p, x, y, z));
    }
    worst = Math.max(worst, best);
  }
  return worst;
}
// The distance from p to the polyline q.
function toPolyline(p, q) {
  let best = Infinity;
  for (let i = 0; i + 1 < q.length; ++i) {
    const d = sub(q[i + 1], q[i]);
    const l2 = dot(d, d);
    const s = l2 > 0 ? Math.min(1, Math.max(0, dot(sub(p, q[i]), d) / l2)) : 0;
    best = Math.min(best, dist(p, q[i].map((x, k) => x + s * d[k])));
  }
  return best;
}
// Spearman's rank correlation.
function rankCorrelation(x, y) {
  const ranks = (v) => {
    const order = v.map((_, i) => i).sort((i, j) => v[i] - v[j]);
    const r = new Array(v.length);
    order.forEach((i, k) => (r[i] = k));
    return r;
  };
  const rx = ranks(x), ry = ranks(y);
  const n = x.length, m = (n - 1) / 2;
  let sxy = 0, sxx = 0, syy = 0;
  for (let i = 0; i < n; ++i) {
    sxy += (rx[i] - m) * (ry[i] - m);
    sxx += (rx[i] - m) ** 2;
    syy += (ry[i] - m) ** 2;
  }
  return sxy / Math.sqrt(sxx * syy);
}
const isDyeGreen = ([r, g, b]) => g > 120 && r < 90 && b < 130; // #16a34a, unlit
const isGrey = ([r, g, b]) => Math.max(r, g, b) - Math.min(r, g, b) < 12;

// Helpers on one page of the designer with a surface shown.
function surfaceHelpers(page) {
  const onSurface = async (p) => {
    const box = await page.locator("#surface canvas").boundingBox();
    const [x, y] = await page.evaluate((q) => window.tvf.surface(q), p);
    return [box.x + x, box.y + y];
  };
  // The colours of the picture at world points (after the next animation frame).
  const pixels = (points) =>
    page.evaluate(async (pts) => {
      await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
      const { data, width, scale } = window.tvf.pixels();
      return pts.map((p) => {
        const [x, y] = window.tvf.surface(p).map((v) => Math.round(v * scale));
        return Array.from(data.slice(4 * (y * width + x), 4 * (y * width + x) + 3));
      });
    }, points);
  const visible = (points) => page.evaluate((pts) => pts.map((p) => window.tvf.surfaceVisible(p)), points);
  const waitFtle = (direction, t) =>
    page.waitForFunction(
      ([dir, time]) => {
        const f = window.tvf.lcs.ftle;
        return f && f.direction === dir && Math.abs(f.t - time) < 1e-9;
      },
      [direction, t],
      { timeout: 120000 },
    );
  return { onSurface, pixels, visible, waitFtle };
}

// The FTLE overlay on the surface: the page's answer is /api/ftle's, the legend is there,
// and the picture's brightness over the vertices the camera sees follows σ.
async function checkFtle(page, h, mesh, t, horizon, minCorrelation, what) {
  const mine = await page.evaluate(() => window.tvf.lcs.ftle);
  const api = await page.evaluate(([time, T]) => fetch(`api/ftle?t=${time}&horizon=${T}&direction=forward`).then((r) => r.json()), [t, horizon]);
  const n = mesh.vertices.length / 3;
  check(mine.values.length === n && api.values.length === n, `${what}: σ at each of the ${n} vertices`);
  check(JSON.stringify(mine.range) === JSON.stringify(api.range) && mine.values.every((v, i) => v === api.values[i]),
    `${what}: the overlay is /api/ftle's answer (colour range ${api.range.map((v) => v.toFixed(3)).join("–")}, which the legend shows)`);
  const legend = await page.evaluate(() => {
    const c = document.getElementById("surface-legend");
    const g = c.getContext("2d");
    const at = (x, y) => Array.from(g.getImageData(x, y, 1, 1).data.slice(0, 3));
    return { hidden: c.hidden, lo: at(11, c.height - 40), hi: at(168, c.height - 40) };
  });
  check(!legend.hidden && dist(legend.lo, MAGMA_LO) < 30 && dist(legend.hi, MAGMA_HI) < 30,
    `${what}: the legend is shown, magma from ${legend.lo} to ${legend.hi}`);
  // Every few vertices the camera sees.
  const sample = [];
  for (let v = 0; v < n; v += Math.max(1, Math.floor(n / 600))) if (api.values[v] !== null) sample.push(v);
  const points = sample.map((v) => [0, 1, 2].map((k) => mesh.vertices[3 * v + k]));
  const seen = await visible(page, points);
  const vs = sample.filter((_, i) => seen[i]);
  const ps = points.filter((_, i) => seen[i]);
  const px = await h.pixels(ps);
  // σ averaged over the vertex and its neighbours: a pixel at a vertex of a fine mesh mixes
  // the colours of the faces around it (the bunny's edges are about two pixels long).
  const ring = new Map(vs.map((v) => [v, [v]]));
  for (let f = 0; f < mesh.faces.length; f += 3)
    for (let k = 0; k < 3; ++k) {
      const r = ring.get(mesh.faces[f + k]);
      if (r) r.push(mesh.faces[f + (k + 1) % 3], mesh.faces[f + (k + 2) % 3]);
    }
  const sigma = vs.map((v) => {
    const known = ring.get(v).map((w) => api.values[w]).filter((x) => x !== null);
    return known.reduce((acc, x) => acc + x, 0) / known.length;
  });
  const bright = px.map((c) => c[0] + c[1] + c[2]);
  const rho = rankCorrelation(sigma, bright);
  const sorted = [...bright].sort((p, q) => p - q);
  const spread = sorted[Math.floor(0.95 * sorted.length)] - sorted[Math.floor(0.05 * sorted.length)];
  const coloured = px.filter((c) => !isGrey(c)).length;
  // (The shading, a factor 0.75–1, blurs the order where σ varies little: on the bunny most
  // of σ lies in a narrow band; measured 0.89 on the sphere, 0.64 on the bunny, where σ
  // shuffled over the same vertices gives |ρ| < 0.2.)
  check(vs.length > 100 && rho > minCorrelation, `${what}: over ${vs.length} vertices in view the picture's brightness follows σ (rank correlation ${rho.toFixed(3)})`);
  check(spread > 150 && coloured > 0.5 * px.length, `${what}: the colours vary over the mesh (brightness 5th–95th percentile spread ${spread} of 765; ${coloured} of ${px.length} not grey)`);
  return { points: ps, sigma };
}
function visible(page, points) {
  return page.evaluate((pts) => pts.map((p) => window.tvf.surfaceVisible(p)), points);
}

// A dye streakline at time t from a click at p: newest point at the click, on the mesh,
// carried away, drawn.
async function checkDye(page, h, mesh, index, p, t, near, clickTol, what) {
  await page.waitForFunction(([i, time]) => {
    const d = window.tvf.lcs.dye[i];
    return d && Math.abs(d.t - time) < 1e-9;
  }, [index, t], { timeout: 120000 });
  const { dye, seed } = await page.evaluate((i) => ({ dye: window.tvf.lcs.dye[i], seed: window.tvf.lcs.seeds[i] }), index);
  check(seed.length === 3 && dist(seed, p) < clickTol, `${what}: the seed is the clicked point (${dist(seed, p).toExponential(2)} from it)`);
  const newest = dye.points[dye.points.length - 1];
  check(dye.points.length > 10 && dist(newest, seed) < 1e-3, `${what}: ${dye.points.length} points (${dye.released} released, ${dye.left} left), the newest at the seed (${dist(newest, seed).toExponential(2)})`);
  const off = offMesh(mesh, dye.points, near);
  check(off < 1e-6, `${what}: every point lies on the mesh (at most ${off.toExponential(2)} from it)`);
  const spread = Math.max(...dye.points.map((q) => dist(q, seed)));
  check(spread > near, `${what}: the dye is carried away from the seed (up to ${spread.toFixed(3)})`);
  const shown = dye.points.filter((_, i) => i % 3 === 0);
  const seen = await visible(page, shown);
  const inView = shown.filter((_, i) => seen[i]);
  const px = await h.pixels(inView);
  const green = px.filter(isDyeGreen).length;
  check(inView.length >= 3 && green >= 0.6 * inView.length, `${what}: drawn on the mesh (${green} of ${inView.length} points in view dye-green)`);
  return dye;
}

async function sphereCase(browser) {
  const dir = tempDir("tvf-e2e-surface-lcs-");
  const server = await startServer(a.tvf, dir);
  let page;
  try {
    page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    const errors = [];
    page.on("pageerror", (e) => errors.push(e.message));
    await page.goto(server.url);
    const d = new Designer(page, server.url);
    const h = surfaceHelpers(page);
    await d.settled();
    const message = async () => (await page.textContent("#message")).trim();
    const applyScene = (edit) => d.editScene(edit);
    await d.change(() => page.selectOption("#domain", "sphere"));
    // The camera looks at the sphere from (0.2, −1, 0.6): the elements on the side it sees.
    const at = (v) => unit(v).map((x) => Math.round(x * 1e4) / 1e4);
    await applyScene((s) => {
      s.time.frames = 41;
      s.generator = "basis";
      s.falloff = 10;
      s.elements = [
        { kind: "singular", type: "source", path: [[...at([-0.55, -1, 0.35]), 0]] },
        { kind: "singular", type: "saddle", path: [[...at([0.05, -1, 0.4]), 0]] },
        { kind: "singular", type: "sink", path: [[...at([0.55, -1, 0.1]), 0], [...at([0.5, -1, 0.7]), 1]] },
      ];
    });
    const mesh = await page.evaluate(() => fetch("api/mesh").then((r) => r.json()));
    const edge = 0.08; // the mean edge length of the 4-times subdivided unit sphere is about 0.075
    check(await page.locator("#lcs-controls").isVisible(), "the LCS controls are shown on a surface");

    // ---- the FTLE overlay ----------------------------------------------------------------
    await d.goto(0);
    await d.settled();
    await page.fill("#lcs-horizon", "0.5");
    await page.dispatchEvent("#lcs-horizon", "change");
    await page.selectOption("#lcs-mode", "forward");
    await h.waitFtle("forward", 0);
    const ms = await page.evaluate(() => [window.tvf.lcs.lastUpdateMs, window.tvf.lcs.ftle.seconds]);
    console.log(`FTLE forward at t = 0, T = 0.5 on the sphere (${mesh.vertices.length / 3} vertices): ${ms[0].toFixed(0)} ms from request to colours (${(ms[1] * 1000).toFixed(0)} ms on the server)`);
    const f = await checkFtle(page, h, mesh, 0, 0.5, 0.75, "sphere, FTLE forward at t = 0");
    await d.shot(a.out, "surface_lcs_01_sphere_ftle.png");
    // Off: the moving texture's grey again.
    await page.selectOption("#lcs-mode", "off");
    await page.waitForFunction(() => !window.tvf.lcs.ftle);
    const grey = (await h.pixels(f.points)).filter(isGrey).length;
    check(grey > 0.9 * f.points.length && (await page.locator("#surface-legend").isHidden()),
      `turned off, the mesh is the grey texture again (${grey} of ${f.points.length}) and the legend goes`);

    // ---- dye: a streakline and a timeline ------------------------------------------------
    await d.goto(20); // t = 0.5
    await d.settled();
    await d.tool("dye");
    const seed = at([-0.3, -1, 0.15]);
    await page.mouse.click(...(await h.onSurface(seed)));
    const dye5 = await checkDye(page, h, mesh, 0, seed, 0.5, edge, 0.015, "sphere, dye at t = 0.5");
    await d.shot(a.out, "surface_lcs_02_sphere_dye.png");
    await d.goto(10); // t = 0.25: a younger streak
    const dye25 = await checkDye(page, h, mesh, 0, seed, 0.25, edge, 0.015, "sphere, dye at t = 0.25");
    check(dye25.points.length < dye5.points.length, `at t = 0.25 the streak is younger (${dye25.points.length} < ${dye5.points.length} points)`);
    // A timeline dragged at t = 0.25 across the saddle's region.
    const [p0, p1] = [at([-0.2, -1, 0.55]), at([0.3, -1, 0.6])];
    const [x0, y0] = await h.onSurface(p0);
    const [x1, y1] = await h.onSurface(p1);
    await page.mouse.move(x0, y0);
    await page.mouse.down();
    await page.mouse.move(x1, y1, { steps: 12 });
    await page.mouse.up();
    await page.waitForFunction(() => window.tvf.lcs.timelines.length === 1 && Math.abs(window.tvf.lcs.timelines[0].t - 0.25) < 1e-9, null, { timeout: 120000 });
    const drawn = await page.evaluate(() => window.tvf.lcs.timelines[0]);
    const line = await page.evaluate(() => window.tvf.lcs.lines[0].line);
    const chord = Math.max(...drawn.points.map((q) => toPolyline(q, line)));
    check(drawn.points.length >= 50 && dist(drawn.points[0], line[0]) < 1e-3 && dist(drawn.points.at(-1), line[1]) < 1e-3 && chord < 0.05,
      `a Dye drag draws a timeline: at its time the shortest path over the mesh between the drag's ends (${drawn.points.length} points, within ${chord.toFixed(3)} of the chord)`);
    check(offMesh(mesh, drawn.points, edge) < 1e-6, "its points lie on the mesh");
    await d.goto(30); // t = 0.75
    await page.waitForFunction(() => Math.abs(window.tvf.lcs.timelines[0]?.t - 0.75) < 1e-9, null, { timeout: 120000 });
    const carried = await page.evaluate(() => window.tvf.lcs.timelines[0]);
    const moved = Math.max(...carried.points.map((q) => toPolyline(q, line)));
    check(moved > 0.05 && offMesh(mesh, carried.points, edge) < 1e-6, `half a time unit later it is carried off the segment (up to ${moved.toFixed(3)}) and still on the mesh`);
    await page.selectOption("#lcs-mode", "forward");
    await h.waitFtle("forward", 0.75);
    await d.shot(a.out, "surface_lcs_03_sphere_dye_timeline_ftle.png");
    await page.selectOption("#lcs-mode", "off");
    await page.click("#dye-clear");
    await page.waitForFunction(() => window.tvf.lcs.seeds.length === 0 && window.tvf.lcs.dye.length === 0);

    // ---- the Streakline tool on the sphere -------------------------------------------------
    await d.goto(32); // t = 0.8
    await d.settled();
    await d.tool("streakline");
    const sketch = [];
    for (let k = 0; k <= 16; ++k) {
      const u = k / 16;
      sketch.push(at([-0.6 + 1.0 * u, -1, -0.1 + 0.2 * Math.sin(2 * Math.PI * u)]));
    }
    await d.change(async () => {
      const pts = [];
      for (const q of sketch) pts.push(await h.onSurface(q));
      await page.mouse.move(...pts[0]);
      await page.mouse.down();
      for (const q of pts.slice(1)) await page.mouse.move(...q, { steps: 4 });
      await page.mouse.up();
    }, 120000);
    const s = (await d.scene()).scene;
    const e = s.elements.at(-1);
    check(e.kind === "streakline" && e.points.length === 12 && e.points.every((q) => q.length === 3) && e.t === 0.8 && e.from === 0.3 && s.generator === "spacetime",
      `the drag sketches a streakline element at t = 0.8 of 12 [x, y, z] points, released from t = 0.3, spacetime generator: "${await message()}"`);
    check(dist(e.points[0], sketch[0]) < 0.03, "its seed where the drag started");
    const traced = await page.evaluate((el) =>
      fetch("api/streakline", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ seed: el.points[0], from: el.from, to: el.t }) }).then((r) => r.json()), e);
    const hausdorff = Math.max(...traced.points.map((q) => toPolyline(q, e.points)), ...e.points.map((q) => toPolyline(q, traced.points)));
    const mean = traced.points.reduce((acc, q) => acc + toPolyline(q, e.points), 0) / traced.points.length;
    check(traced.left === 0 && hausdorff < 1.5 * edge, `the dye traced in the new field lies on the sketch (Hausdorff ${hausdorff.toFixed(4)}, mean ${mean.toFixed(4)}; an edge is about ${edge})`);
    // The dye shown on it.
    await d.tool("dye");
    await page.mouse.click(...(await h.onSurface(e.points[0])));
    await page.waitForFunction(() => window.tvf.lcs.dye.length === 1, null, { timeout: 120000 });
    await d.shot(a.out, "surface_lcs_04_sphere_streakline_sketched.png");
    check(errors.length === 0, `no errors in the page${errors.length ? ": " + errors.join("; ") : ""}`);
  } catch (e) {
    await reportFailure(e, page, server, `${a.out}/surface_lcs_failure.png`);
    throw e;
  } finally {
    await page?.close();
    await stopServer(server);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

async function bunnyCase(browser) {
  if (process.argv.includes("--no-bunny")) {
    console.log("(--no-bunny: the bunny's part is left out)");
    return;
  }
  if (!fs.existsSync(path.join(bunny, "bunny.off"))) {
    console.log(`(no ${bunny}/bunny.off: the bunny's part is skipped; scripts/install-deps.sh extracts it)`);
    return;
  }
  const dir = tempDir("tvf-e2e-surface-lcs-bunny-");
  fs.copyFileSync(path.join(bunny, "bunny.off"), path.join(dir, "bunny.off"));
  fs.copyFileSync(path.join(bunny, "scene.json"), path.join(dir, "scene.json"));
  const server = await startServer(a.tvf, dir);
  let page;
  try {
    page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
    const errors = [];
    page.on("pageerror", (e) => errors.push(e.message));
    await page.goto(server.url);
    const d = new Designer(page, server.url);
    const h = surfaceHelpers(page);
    await d.settled(240000);
    const mesh = await page.evaluate(() => fetch("api/mesh").then((r) => r.json()));
    // The bunny's mean edge length (about 0.0055 on its 0.49-wide body).
    let total = 0;
    for (let f = 0; f < mesh.faces.length; f += 3)
      for (const [i, j] of [[0, 1], [1, 2], [2, 0]])
        total += dist(mesh.vertices.slice(3 * mesh.faces[f + i], 3 * mesh.faces[f + i] + 3), mesh.vertices.slice(3 * mesh.faces[f + j], 3 * mesh.faces[f + j] + 3));
    const edge = total / mesh.faces.length;
    // The camera starts below the bunny; a right drag up by 105 pixels orbits it (68°)
    // to look at the flank that the vortex crosses.
    const box = await page.locator("#surface canvas").boundingBox();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.down({ button: "right" });
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2 - 105, { steps: 10 });
    await page.mouse.up({ button: "right" });
    await d.goto(15); // t = 15/59
    await d.settled(240000);
    await page.fill("#lcs-horizon", "0.5");
    await page.dispatchEvent("#lcs-horizon", "change");
    await page.selectOption("#lcs-mode", "forward");
    await page.waitForFunction(() => window.tvf.lcs.ftle?.direction === "forward", null, { timeout: 240000 });
    const ms = await page.evaluate(() => [window.tvf.lcs.lastUpdateMs, window.tvf.lcs.ftle.seconds, window.tvf.lcs.ftle.t]);
    console.log(`FTLE forward at t = ${ms[2].toFixed(3)}, T = 0.5 on the bunny (${mesh.vertices.length / 3} vertices): ${ms[0].toFixed(0)} ms from request to colours (${(ms[1] * 1000).toFixed(0)} ms on the server)`);
    await checkFtle(page, h, mesh, ms[2], 0.5, 0.5, `bunny, FTLE forward at t = ${ms[2].toFixed(3)}`);
    await d.shot(a.out, "surface_lcs_05_bunny_ftle.png");
    // Dye from three seeds on the bunny's flank and back (the vortex crosses the flank),
    // seen at a later time.
    await page.selectOption("#lcs-mode", "off");
    await page.waitForFunction(() => !window.tvf.lcs.ftle);
    await d.goto(45);
    await d.settled(240000);
    const tDye = 45 / 59; // the frame's time (range [0, 1], 60 frames)
    await d.tool("dye");
    // Seeds: vertices the camera sees around the vortex's path across the flank
    // ((−0.29, −0.11, 0.30) at t = 0 to (0.27, −0.11, 0.31) at t = 1) and near the saddle.
    const near = (p) => {
      let best = 0;
      for (let v = 0; 3 * v < mesh.vertices.length; ++v)
        if (dist(mesh.vertices.slice(3 * v, 3 * v + 3), p) < dist(mesh.vertices.slice(3 * best, 3 * best + 3), p)) best = v;
      return mesh.vertices.slice(3 * best, 3 * best + 3);
    };
    const candidates = [
      [0.05, -0.2, 0.3], [-0.1, -0.2, 0.3], [0.2, -0.2, 0.28], [0.05, -0.15, 0.33], [-0.1, -0.3, 0.25],
      [0.15, -0.3, 0.25], [0.3, -0.35, 0.0], [0.2, -0.45, 0.1],
    ].map(near);
    const seen = await visible(page, candidates);
    const seeds = candidates.filter((_, i) => seen[i]).slice(0, 3);
    check(seeds.length >= 2, `${seeds.length} seed points on the bunny in view`);
    for (const [i, p] of seeds.entries()) {
      await page.mouse.click(...(await h.onSurface(p)));
      await page.waitForFunction((n) => window.tvf.lcs.seeds.length === n, i + 1);
    }
    for (const [i, p] of seeds.entries()) await checkDye(page, h, mesh, i, p, tDye, 3 * edge, 0.01, `bunny, dye ${i} at t = ${tDye.toFixed(3)}`);
    // A timeline dragged between the first two seeds at t = 0.51, seen at t = 0.76.
    await d.goto(30);
    await d.settled(240000);
    const [q0, q1] = [await h.onSurface(seeds[0]), await h.onSurface(seeds[1])];
    await page.mouse.move(...q0);
    await page.mouse.down();
    await page.mouse.move(...q1, { steps: 12 });
    await page.mouse.up();
    await page.waitForFunction(() => window.tvf.lcs.timelines.length === 1, null, { timeout: 240000 });
    await d.goto(45);
    await page.waitForFunction((t) => Math.abs(window.tvf.lcs.timelines[0]?.t - t) < 1e-9 && Math.abs(window.tvf.lcs.dye[0]?.t - t) < 1e-9, tDye, { timeout: 240000 });
    const timeline = await page.evaluate(() => window.tvf.lcs.timelines[0]);
    const off = offMesh(mesh, timeline.points, 3 * edge);
    check(timeline.points.length >= 50 && off < 1e-6, `a timeline on the bunny: ${timeline.points.length} points, on the mesh (at most ${off.toExponential(2)} off)`);
    await d.shot(a.out, "surface_lcs_06_bunny_dye.png");
    await page.selectOption("#lcs-mode", "backward");
    await page.waitForFunction(() => window.tvf.lcs.ftle?.direction === "backward", null, { timeout: 240000 });
    await d.shot(a.out, "surface_lcs_07_bunny_dye_ftle_backward.png");
    check(errors.length === 0, `no errors in the page${errors.length ? ": " + errors.join("; ") : ""}`);
  } catch (e) {
    await reportFailure(e, page, server, `${a.out}/surface_lcs_bunny_failure.png`);
    throw e;
  } finally {
    await page?.close();
    await stopServer(server);
    fs.rmSync(dir, { recursive: true, force: true });
  }
}

const browser = await launch(a.chromium);
let failed = false;
try {
  await sphereCase(browser);
  await bunnyCase(browser);
} catch {
  failed = true;
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
