// End-to-end test of the surface designer's Move bifurcation and Deform streamline tools
// (issue 7: the same tools on surfaces, points picked on the surface). On the sphere:
// - a saddle–sink creation is placed with the Bifurcation tool by press-and-drag (its
//   axis and size along the drag): the analysis finds it at the press and the time, and
//   after it the sink runs towards the drag's end; it is picked in the list ("go
//   to"), and moved with the Move bifurcation tool by a click elsewhere on the surface:
//   the analysis finds it there and no longer at its old place;
// - a representative streamline of a storm (counter-clockwise centre) is dragged on the
//   surface by the last frame and turned by 1.2 rad: the key's translate comes from the
//   server's log map, and the last frame's field at the drag's end runs along the turned
//   streamline, not along the base field there;
// - the whole field turned by π (Rotate field): the centre turns the other way;
// - a key frame's source placed by a drag on the sphere: the key frame's field has it there.
// Screenshots go to --out (looked at by people, not compared by the test).
// Usage: node e2e/surface_tools.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import fs from "node:fs";
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-surface-tools-");
let failed = false;
let page;

const norm = (v) => Math.hypot(...v);
const unit = (v) => v.map((x) => x / norm(v));
const dot = (u, v) => u.reduce((s, x, k) => s + x * v[k], 0);
const cross = (u, v) => [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
const angle = (u, v) => Math.acos(Math.min(1, Math.max(-1, dot(unit(u), unit(v)))));
// The point at angle t along the great circle from p towards q.
function greatCircle(p, q, t) {
  const u = unit(q.map((x, k) => x - dot(p, q) * p[k]));
  return p.map((x, k) => Math.cos(t) * x + Math.sin(t) * u[k]);
}
// The world vector at the vertex nearest to p, projected onto the sphere's tangent plane at p.
function vectorAt(mesh, frame, p) {
  let best = 0;
  let bestD = Infinity;
  for (let v = 0; 3 * v < mesh.vertices.length; ++v) {
    const d = Math.hypot(...p.map((x, k) => x - mesh.vertices[3 * v + k]));
    if (d < bestD) [best, bestD] = [v, d];
  }
  const w = [0, 1, 2].map((k) => frame.vectors[3 * best + k]);
  const n = unit(p);
  return w.map((x, k) => x - dot(w, n) * n[k]);
}
// v turned by theta counter-clockwise about the outward normal at p (a unit-sphere point).
const turn = (v, p, theta) => v.map((x, k) => Math.cos(theta) * x + Math.sin(theta) * cross(unit(p), v)[k]);
// v parallel-transported along the great circle from p to q (the rotation taking p to q).
function transport(v, p, q) {
  const axis = cross(p, q);
  if (norm(axis) < 1e-12) return v;
  const k = unit(axis);
  const th = angle(p, q);
  const kv = cross(k, v);
  return v.map((x, i) => x * Math.cos(th) + kv[i] * Math.sin(th) + k[i] * dot(k, v) * (1 - Math.cos(th)));
}
const cosine = (u, v) => dot(u, v) / (norm(u) * norm(v));

try {
  page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  const d = await Designer.open(page, server.url);
  const mesh = () => page.evaluate(() => fetch("api/mesh").then((r) => r.json()));
  const frameAt = (j) => page.evaluate((k) => fetch(`api/frame/${k}`).then((r) => r.json()), j);
  const analysis = () => page.evaluate(() => fetch("api/analysis").then((r) => r.json()));
  const message = async () => (await page.textContent("#message")).trim();
  const applyScene = (edit) => d.editScene(edit);

  // ---- moving a bifurcation on the sphere -----------------------------------------------
  await d.change(() => page.selectOption("#domain", "sphere"));
  // 48 frames (short solves, and enough that the edit's window, ±10 % of the time range,
  // holds a few frames); the basis generator, whose bifurcation element is the
  // paper's local model (as in examples/20_sphere_bifurcation_move).
  await applyScene((s) => {
    s.time.frames = 48;
    s.generator = "basis";
    s.falloff = 120;
  });
  check(await page.locator("#surface canvas").isVisible(), "the sphere is shown");
  const onSurface = (p) => d.onSurface(p);
  const clickOnSurface = (p) => d.clickSurface(p);
  const dragOnSurface = async (p, q, n = 10) => {
    const pts = [];
    for (let k = 0; k <= n; ++k) pts.push(await onSurface(greatCircle(p, q, (angle(p, q) * k) / n)));
    await page.mouse.move(...pts[0]);
    await page.mouse.down();
    for (const s of pts.slice(1)) await page.mouse.move(...s, { steps: 4 });
    await page.mouse.up();
  };
  // The camera looks at the sphere from (0.2, −1, 0.6): work on the side it sees.
  const old = unit([-0.35, -1, 0.35]);
  const target = unit([0.3, -1, 0.55]);
  await d.goto(19); // t = 19/47 ≈ 0.40
  await d.settled();
  await d.tool("bifurcation");
  await page.selectOption("#bifurcation-type", "saddle_sink_creation");
  // Placed by press-and-drag: where the press is, its pair moving along the drag (axis and
  // scale from the server's log map around the press), at the current time.
  const axisEnd = greatCircle(old, unit([-0.35, -1, 0.1]), 0.2);
  await d.change(() => dragOnSurface(old, axisEnd, 6), 60000);
  const placed = (await d.scene()).scene.elements.at(-1);
  const t0 = placed.at[3];
  check(placed.kind === "bifurcation" && placed.at.length === 4 && angle(placed.at.slice(0, 3), old) < 0.03 && Math.abs(t0 - 19 / 47) < 0.002,
    `the drag places a bifurcation at its start and the current time: "${await message()}"`);
  check(Math.abs(placed.scale - 0.2) < 0.03, `as large as the drag is long (scale ${placed.scale} for 0.2 rad)`);
  let an = await analysis();
  const near = (list, p) => Math.min(Infinity, ...list.map((b) => angle(b.position, p)));
  const designed = an.bifurcations.filter((b) => angle(b.position, old) < 0.15);
  check(designed.length === 1, `the analysis finds the placed bifurcation (${near(an.bifurcations, old).toFixed(3)} rad from the press)`);
  check(designed.length === 1 && Math.abs(designed[0].t - t0) < 0.05, `at its time (t = ${designed[0]?.t.toFixed(3)}, designed ${t0.toFixed(3)})`);
  // After it the sink runs ahead along the drag, the saddle behind (axis +x of the template).
  const after = (await frameAt(30)).singularities.filter((x) => angle(x.position, old) < 0.3);
  const sink = after.find((x) => x.type === "sink");
  const saddle = after.find((x) => x.type === "saddle");
  check(sink && saddle && angle(sink.position, axisEnd) < angle(saddle.position, axisEnd) - 0.05 && angle(sink.position, axisEnd) < angle(old, axisEnd),
    `at t = 30/47 the sink lies towards the drag's end, the saddle away from it (${sink && angle(sink.position, axisEnd).toFixed(3)} vs ${saddle && angle(saddle.position, axisEnd).toFixed(3)} rad)`);
  const i = an.bifurcations.reduce((bi, b, k) => (angle(b.position, old) < angle(an.bifurcations[bi].position, old) ? k : bi), 0);
  await page.locator("#bifurcations .bifurcation").nth(i).locator("button", { hasText: "go to" }).click();
  check(await page.evaluate(() => window.tvf.state.selectedBifurcation) === i, "it is picked in the list");
  await d.settled();
  await d.shot(a.out, "surface_tools_01_bifurcation_placed.png");
  // Moved to a frame just after it, where the pair exists.
  await d.goto(20);
  await d.settled();
  await d.tool("move-bifurcation");
  await d.change(() => clickOnSurface(target), 60000);
  const edited = (await d.scene()).scene;
  const e = edited.edits.at(-1);
  check(e?.op === "move_bifurcation" && e.at.length === 4 && e.to.length === 4, `a click on the sphere sends move_bifurcation with [x, y, z, t] places: "${await message()}"`);
  check(angle(e.to.slice(0, 3), target) < 0.05, "to the clicked point");
  an = await analysis();
  check(near(an.bifurcations, target) < 0.15, `the analysis finds the bifurcation at its new place (${near(an.bifurcations, target).toFixed(3)} rad)`);
  check(near(an.bifurcations, old) > 0.3, `and none at its old place (nearest ${near(an.bifurcations, old).toFixed(3)} rad)`);
  await d.goto(21);
  await d.settled();
  await d.shot(a.out, "surface_tools_02_bifurcation_moved.png");

  // ---- a streamline deformation key set by a drag on the sphere --------------------------
  await applyScene((s) => {
    s.time.frames = 24;
    s.elements = [];
    s.edits = [];
    s.generator = "constrained";
    s.falloff = 10;
    s.solver = { ...(s.solver ?? {}), region_radius: 0.15 };
  });
  const storm = unit([0, -1, 0.45]);
  await d.goto(0);
  await d.tool("singular");
  await page.selectOption("#singular-type", "ccw_center");
  await page.fill("#life-start", "0");
  await d.change(() => clickOnSurface(storm));
  // The seed 0.3 rad from the storm, on the +x side; dragged 0.3 rad further out.
  const east = unit([1, 0, 0].map((x, k) => x - dot([1, 0, 0], storm) * storm[k]));
  const seed = greatCircle(storm, storm.map((x, k) => x + east[k]), 0.3);
  const to = greatCircle(storm, storm.map((x, k) => x + east[k]), 0.6);
  await d.goto(23);
  await d.tool("deform");
  await page.fill("#deform-turn", "1.2");
  await d.change(() => dragOnSurface(seed, to), 90000);
  const s = (await d.scene()).scene;
  const sl = s.deform?.streamlines?.[0];
  const key = sl?.keys?.[0];
  check(s.generator === "deform" && s.deform.base.elements.length === 1 && s.deform.streamlines.length === 1, `the drag makes a deformed streamline over the storm: "${await message()}"`);
  check(sl.seed.length === 3 && angle(sl.seed, seed) < 0.03, "its seed is where the drag started, [x, y, z]");
  check(key.t === 1 && key.rotate === 1.2 && key.translate.length === 3, "a key at the last time, turned by 1.2, with a world-vector translate");
  check(Math.abs(dot(key.translate, unit(sl.seed))) < 0.03 && Math.abs(norm(key.translate) - angle(sl.seed, to)) < 0.04,
    `the translate is tangent at the seed and as long as the geodesic to the drag's end (${norm(key.translate).toFixed(3)} vs ${angle(sl.seed, to).toFixed(3)})`);
  const sphere = await mesh();
  const base0 = vectorAt(sphere, await frameAt(0), seed);
  const baseTo = vectorAt(sphere, await frameAt(0), to);
  const last = vectorAt(sphere, await frameAt(23), to);
  const want = transport(turn(base0, seed, 1.2), seed, to);
  const cFollow = cosine(last, want);
  const cBase = cosine(last, baseTo);
  check(cFollow > 0.9, `at t = 1 the field at the drag's end runs along the moved, turned streamline (cos ${cFollow.toFixed(3)})`);
  check(cBase < 0.6, `not along the base field there (cos ${cBase.toFixed(3)})`);
  await d.settled();
  await d.shot(a.out, "surface_tools_03_streamline_deformed.png");
  // A drag to the far side of the sphere is beyond the seed's chart: refused in one sentence.
  const rev = (await d.status()).revision;
  const post = (q) =>
    page.evaluate((body) => fetch("api/seed_translation", { method: "POST", headers: { "Content-Type": "application/json" }, body }).then(async (r) => [r.status, await r.json()]), JSON.stringify(q));
  const bad = await post({ seed: sl.seed.slice(0, 2), to: to });
  check(bad[0] === 400, `a malformed seed is a 400: "${bad[1].error}"`);
  const far = await post({ seed: sl.seed, to: sl.seed.map((x) => -x) });
  check(far[0] === 422 && /too far from the seed/.test(far[1].error), `a point beyond the chart is refused: ${far[0]} "${far[1].error}"`);
  check((await d.status()).revision === rev, "and changes nothing");

  // ---- the whole field turned by π on the sphere -----------------------------------------
  await d.change(() => page.click("#rotate-field"), 90000);
  // The frames name a centre's turn by the field: counter-clockwise about the outward
  // normal at first, clockwise at the end, seen from a point just west of the storm.
  const west = greatCircle(storm, storm.map((x, k) => x - east[k]), 0.12);
  const ccw = cross(unit(west), west.map((x, k) => x - storm[k]));
  const spin = async (j) => cosine(vectorAt(sphere, await frameAt(j), west), ccw);
  const centre = async (j) => (await frameAt(j)).singularities.some((x) => angle(x.position, storm) < 0.15 && x.type === "center");
  const [c0, c1] = [await spin(0), await spin(23)];
  check((await centre(0)) && (await centre(23)), "a centre at the storm at the first and the last time");
  check(c0 > 0.8 && c1 < -0.8, `the storm turned by π turns the other way at the end (cos ${c0.toFixed(3)} → ${c1.toFixed(3)})`);
  await d.goto(12);
  await d.settled();
  await d.shot(a.out, "surface_tools_04_field_rotated_mid.png");
  // ---- a key frame's singularity placed on the sphere by press-and-drag ------------------
  await applyScene((s) => {
    s.time.frames = 12;
    s.elements = [];
    s.edits = [];
    delete s.deform;
    s.keyframes = [];
    s.generator = "constrained";
  });
  await d.goto(6);
  await d.settled();
  await d.tool("singular");
  await page.selectOption("#singular-type", "source");
  await page.check("#keyframe-mode");
  const keyAt = unit([0.15, -1, 0.3]);
  await d.change(() => dragOnSurface(keyAt, greatCircle(keyAt, [0, 0, 1], 0.15), 4), 120000);
  const ks = (await d.scene()).scene;
  const k = ks.keyframes?.[0];
  check(ks.generator === "spacetime" && ks.keyframes.length === 1 && Math.abs(k.t - 6 / 11) < 1e-3 && k.elements.length === 1,
    `the drag puts a key frame at the current time (t = ${k?.t}) with one element, spatio-temporal generator: "${await message()}"`);
  check(k.elements[0].type === "source" && k.elements[0].at.length === 3 && angle(k.elements[0].at, keyAt) < 0.03,
    "a source where the press was, [x, y, z]");
  await d.settled();
  const keyFrame = await frameAt(6);
  const found = keyFrame.singularities.filter((x) => angle(x.position, keyAt) < 0.1);
  check(found.length === 1 && found[0].type === "source", `the key frame's field has the source there (${found.map((x) => `${x.type} ${angle(x.position, keyAt).toFixed(3)} rad`).join(", ")})`);
  await page.uncheck("#keyframe-mode");
  await d.shot(a.out, "surface_tools_05_keyframe_source.png");
  check(errors.length === 0, `no errors in the page${errors.length ? ": " + errors.join("; ") : ""}`);
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, `${a.out}/surface_tools_failure.png`);
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
