// The "must show", played by a script the way a new user would do it: the
// paper's Fig. 9 storms on the plane. Key frame at t = 0 with two counter-clockwise
// vortices, key frame at t = 1 with one vortex between their places; the spatio-temporal
// optimization moves them together and merges them. Then the video is rendered.
// Usage: node e2e/storms.e2e.mjs --tvf PATH/TO/tvf [--out DIR]
import fs from "node:fs";
import { check, Designer, finish, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-storms-");
let failed = false;
let page;
try {
  page = await browser.newPage({ viewport: { width: 1280, height: 860 } });
  const d = await Designer.open(page, server.url);
  const started = Date.now();
  await d.change(() => page.click("#new"));

  // Key frame at t = 0: two storms.
  await d.tool("singular");
  await page.selectOption("#singular-type", "ccw_center");
  await page.check("#keyframe-mode");
  await d.goto(0);
  await d.change(() => d.click([-0.45, 0.1]));
  await d.change(() => d.click([0.45, -0.1]));
  // Key frame at t = 1: one storm between them.
  await d.goto(99);
  const st = await d.change(() => d.click([0, 0]), 60000);
  const scene = (await d.scene()).scene;
  check(scene.generator === "spacetime" && scene.keyframes.length === 2, "two key frames, spacetime generator");
  check(scene.keyframes[0].elements.length === 2 && scene.keyframes[1].elements.length === 1, "two storms, then one");
  console.log(`solved in ${st.seconds.toFixed(2)} s (${st.method})`);
  const analysis = await page.evaluate(() => fetch("api/analysis").then((r) => r.json()));
  const centers = (j) => analysis.singularities.filter((s) => s.frame === j && s.index === 1).length;
  check(centers(0) === 2 && centers(99) === 1, `two vortices at the start (${centers(0)}), one at the end (${centers(99)})`);
  check(analysis.bifurcations.some((b) => b.kind === "cancellation"), "they merge: a cancellation bifurcation");
  for (const j of [0, 40, 70, 99]) {
    await d.goto(j);
    await d.settled();
    await d.shot(a.out, `storms_${String(j).padStart(2, "0")}.png`);
  }
  await page.click("#render-video");
  await page.waitForSelector("#video-link:not([hidden])", { timeout: 120000 });
  const size = fs.statSync(`${dir}/video.mp4`).size;
  check(size > 10000, `video.mp4 rendered (${size} bytes)`);
  await d.shot(a.out, "storms_video_done.png");
  console.log(`designed and rendered in ${((Date.now() - started) / 1000).toFixed(1)} s of script time`);
  if (process.env.KEEP_VIDEO) fs.copyFileSync(`${dir}/video.mp4`, process.env.KEEP_VIDEO);
} catch (e) {
  failed = true;
  console.error(e.message);
  if (page) await page.screenshot({ path: `${a.out}/failure.png` }).catch(() => {});
  if (page)
    console.error(
      await page
        .evaluate(() => JSON.stringify({ frame: window.tvf.state.frames.get(window.tvf.state.frame)?.singularities, message: document.getElementById("message").textContent }))
        .catch(() => ""),
    );
  console.error(server.output());
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
