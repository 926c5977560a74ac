// End-to-end test of drawing curves (issue 7): a pathline drawn in the space-time view
// (press on the time plane, drag upwards), a pathline and a key-frame streamline drawn on
// the sphere (points picked on the surface), and the video of the surface design rendered
// from the page. Screenshots go to --out (looked at by people, not compared by the test).
// Usage: node e2e/draw.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-draw-");
let failed = false;
let page;

const norm = (v) => Math.hypot(...v);
const unit = (v) => v.map((x) => x / norm(v));
const dot = (u, v) => u.reduce((s, x, k) => s + x * v[k], 0);
// The point at angle t along the great circle from p towards q.
function greatCircle(p, q, t) {
  const u = unit(q.map((x, k) => x - dot(p, q) * p[k]));
  return p.map((x, k) => Math.cos(t) * x + Math.sin(t) * u[k]);
}
// The world vector at the vertex nearest to p.
function vectorNear(mesh, frame, p) {
  let best = 0;
  let bestD = Infinity;
  for (let v = 0; 3 * v < mesh.vertices.length; ++v) {
    const d = Math.hypot(...p.map((x, k) => x - mesh.vertices[3 * v + k]));
    if (d < bestD) [best, bestD] = [v, d];
  }
  return [0, 1, 2].map((k) => frame.vectors[3 * best + k]);
}
const cosine = (u, v) => dot(u, v) / (norm(u) * norm(v));
// Distance from a point to a polyline (2-D).
function toPolyline(p, line) {
  let best = Infinity;
  for (let i = 0; i + 1 < line.length; ++i) {
    const [ax, ay] = line[i];
    const [bx, by] = line[i + 1];
    const l2 = (bx - ax) ** 2 + (by - ay) ** 2;
    const w = l2 > 0 ? Math.min(1, Math.max(0, ((p[0] - ax) * (bx - ax) + (p[1] - ay) * (by - ay)) / l2)) : 0;
    best = Math.min(best, Math.hypot(p[0] - ax - w * (bx - ax), p[1] - ay - w * (by - ay)));
  }
  return best;
}

try {
  page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  const d = await Designer.open(page, server.url);
  const mesh = () => page.evaluate(() => fetch("api/mesh").then((r) => r.json()));
  const frameAt = (j) => page.evaluate((k) => fetch(`api/frame/${k}`).then((r) => r.json()), j);

  // ---- a pathline drawn in the space-time view ------------------------------------------
  await d.change(() => page.click("#new"));
  await d.tool("pathline");
  const st = await page.locator("#spacetime canvas").boundingBox();
  const onView = async (p) => {
    const [x, y] = await page.evaluate((q) => window.tvf.spacetime(q), p);
    return [st.x + x, st.y + y];
  };
  // Press on the time plane (t = 0) at (−0.5, −0.4); drag up (later) and to the right.
  const [sx, sy] = await onView([-0.5, -0.4, 0]);
  const [, topY] = await onView([-0.5, -0.4, 1]);
  const rise = sy - topY;
  const drawn = [[sx, sy], [sx + 25, sy - 0.3 * rise], [sx + 60, sy - 0.55 * rise], [sx + 80, sy - 0.8 * rise]];
  await d.change(async () => {
    await page.mouse.move(...drawn[0]);
    await page.mouse.down();
    for (const q of drawn.slice(1)) await page.mouse.move(...q, { steps: 10 });
    await page.mouse.up();
  });
  const el = (await d.scene()).scene.elements;
  const pl = el[0]?.pathline ?? [];
  check(el.length === 1 && el[0].kind === "regular" && pl.length >= 4 && pl.every((q) => q.length === 3),
    `a drag in the space-time view makes a regular element with (x, y, t) points: ${JSON.stringify(pl)}`);
  check(Math.hypot(pl[0][0] + 0.5, pl[0][1] + 0.4) < 0.03 && Math.abs(pl[0][2]) < 0.01,
    "the pathline starts where the drag pressed on the time plane (−0.5, −0.4, t = 0)");
  check(pl.every((q, i) => i === 0 || q[2] > pl[i - 1][2]) && pl.at(-1)[2] > 0.5 && pl.at(-1)[2] < 0.95,
    `its time rises with the drag (t = ${pl[0][2]} … ${pl.at(-1)[2]})`);
  let worst = 0;
  for (const q of pl) worst = Math.max(worst, toPolyline(await onView(q), drawn));
  check(worst < 4, `every control point lies under the drawn stroke in the view (within ${worst.toFixed(1)} px)`);
  check(pl.at(-1)[0] > pl[0][0] + 0.1, "dragging to the right moved it across the domain");
  // The field carries particles along it: at the middle control point's frame, the vector
  // there points along the pathline's velocity.
  const grid = await mesh();
  const mid = Math.floor(pl.length / 2);
  const jm = Math.round(pl[mid][2] * 99);
  const velocity = [pl[mid + 1][0] - pl[mid - 1][0], pl[mid + 1][1] - pl[mid - 1][1], 0];
  const cPlane = cosine(vectorNear(grid, await frameAt(jm), [pl[mid][0], pl[mid][1], 0]), velocity);
  check(cPlane > 0.9, `the field at t = ${pl[mid][2]} runs along the drawn pathline (cos ${cPlane.toFixed(3)})`);
  await d.goto(jm);
  await d.settled();
  await d.shot(a.out, "draw_01_spacetime_pathline.png");
  await page.locator("#spacetime").screenshot({ path: path.join(a.out, "draw_02_spacetime_view.png") });

  // ---- the sphere: a pathline and a streamline drawn on the surface ---------------------
  await d.change(() => page.selectOption("#domain", "sphere"));
  // Fewer frames, so that the video below stays short.
  await d.editScene((s) => {
    s.time.frames = 24;
  });
  check(await page.locator("#surface canvas").isVisible(), "the sphere is shown");
  const onSurface = (p) => d.onSurface(p);
  const dragOnSurface = async (p, q, angle, n = 12) => {
    const pts = [];
    for (let k = 0; k <= n; ++k) pts.push(await onSurface(greatCircle(p, q, (angle * k) / n)));
    await page.mouse.move(...pts[0]);
    await page.mouse.down();
    for (const s of pts.slice(1)) await page.mouse.move(...s, { steps: 4 });
    await page.mouse.up();
  };
  // The camera looks at the sphere from (0.2, −1, 0.6): draw on the side it sees.
  const p0 = unit([-0.35, -1, 0.25]);
  const q0 = unit([0.6, -0.9, 0.3]);
  await page.fill("#life-start", "0");
  await page.fill("#life-end", "1");
  await d.tool("pathline");
  await d.change(() => dragOnSurface(p0, q0, 0.8));
  const sph = (await d.scene()).scene;
  const line = sph.elements[0]?.pathline ?? [];
  check(sph.elements.length === 1 && sph.elements[0].kind === "regular" && line.length === 8 && line.every((q) => q.length === 4),
    `a drag on the sphere makes a pathline of [x, y, z, t] points (${line.length})`);
  check(line.every((q) => Math.abs(norm(q.slice(0, 3)) - 1) < 0.02), "its points were picked on the surface");
  check(line[0][3] === 0 && line.at(-1)[3] === 1, "it spans the life span 0 … 1");
  check(norm(line[0].slice(0, 3).map((x, k) => x - p0[k])) < 0.05, "it starts where the drag started");
  const sphere = await mesh();
  const m4 = line[4];
  const j4 = Math.round(m4[3] * 23);
  const along = line[5].slice(0, 3).map((x, k) => x - line[3][k]);
  const cPath = cosine(vectorNear(sphere, await frameAt(j4), m4.slice(0, 3)), along);
  check(cPath > 0.9, `the field on the sphere at t = ${m4[3].toFixed(2)} runs along the drawn pathline (cos ${cPath.toFixed(3)})`);

  // A streamline of the key frame at t = 0, lower down.
  await d.goto(0);
  await d.tool("streamline");
  const p1 = unit([0.3, -1, -0.35]);
  const q1 = unit([-0.5, -0.9, -0.1]);
  await d.change(() => dragOnSurface(p1, q1, 0.8));
  const withKey = (await d.scene()).scene;
  const sl = withKey.keyframes?.[0]?.streamlines?.[0]?.points ?? [];
  check(withKey.generator === "spacetime" && withKey.keyframes[0].t === 0 && sl.length === 10 && sl.every((q) => q.length === 3),
    `a drag on the sphere with the Streamline tool makes a key-frame streamline of [x, y, z] points (${sl.length})`);
  check(sl.every((q) => Math.abs(norm(q) - 1) < 0.02), "its points were picked on the surface");
  const cStream = cosine(vectorNear(sphere, await frameAt(0), sl[5]), sl[6].map((x, k) => x - sl[4][k]));
  check(cStream > 0.9, `the field of the key frame runs along the drawn streamline (cos ${cStream.toFixed(3)})`);
  await d.settled();
  await d.shot(a.out, "draw_03_sphere_streamline_pathline.png");
  await d.goto(j4);
  await d.settled();
  await d.shot(a.out, "draw_04_sphere_pathline_mid.png");

  // ---- the video of the surface design, from the page's camera --------------------------
  await page.fill("#video-size", "160"); // small: the surface texture costs about a second a frame at 512²
  await page.click("#render-video");
  await page.waitForFunction(() => !/^(rendering|waiting)/.test(document.getElementById("message").textContent), null, { timeout: 240000 });
  const msg = (await page.textContent("#message")).trim();
  check(/^rendered video\.mp4 of revision \d+: 24 frames/.test(msg) && !(await page.locator("#message.error").count()), `the surface video is rendered: "${msg}"`);
  check(fs.existsSync(`${dir}/video.mp4`) && fs.statSync(`${dir}/video.mp4`).size > 1000, "video.mp4 is in the working folder");
  check(await page.locator("#video-link").isVisible(), "the page links the video");
  try {
    execFileSync("ffmpeg", ["-loglevel", "error", "-y", "-i", `${dir}/video.mp4`, "-vf", "select=eq(n\\,12)", "-frames:v", "1", path.join(a.out, "draw_05_surface_video_frame12.png")]);
    console.log(`screenshot: ${path.join(a.out, "draw_05_surface_video_frame12.png")} (frame 12 of the video)`);
  } catch {
    console.log("(ffmpeg could not extract a frame of the video to look at)");
  }
  check(errors.length === 0, `no errors in the page${errors.length ? ": " + errors.join("; ") : ""}`);
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, `${a.out}/draw_failure.png`);
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
