// End-to-end test of the designer (issue 7): `tvf serve` in a fresh folder, Debian's
// Chromium driven by playwright-core. Open the page, place a vortex and a saddle, draw a
// pathline, play the timeline, cancel the vortex–saddle pair, reload and find the design
// intact. Screenshots go to --out (looked at by people, not compared by the test).
// Usage: node e2e/designer.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import fs from "node:fs";
import { check, Designer, finish, nearest, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-");
let failed = false;
let page;
try {
  page = await browser.newPage({ viewport: { width: 1280, height: 860 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  const d = await Designer.open(page, server.url);
  check((await page.title()) === "tvf designer", "the page opens");
  await d.shot(a.out, "01_demo_scene.png");

  await d.change(() => page.click("#new"));
  check((await d.scene()).scene.elements.length === 0, "New starts an empty design");

  // A vortex and a saddle beside it, both fixed.
  await d.tool("singular");
  await page.selectOption("#singular-type", "ccw_center");
  await d.change(() => d.click([-0.35, 0.3]));
  await page.selectOption("#singular-type", "saddle");
  await d.change(() => d.click([0.15, 0.3]));
  let frame = await d.frame();
  check(nearest(frame, ["center", "repelling_focus", "attracting_focus"], [-0.35, 0.3]) < 0.08, "the vortex is in the field");
  check(nearest(frame, ["saddle"], [0.15, 0.3]) < 0.08, "the saddle is in the field");

  // A pathline drawn along the bottom, from t = 0 to 1.
  await d.tool("pathline");
  await d.change(() => d.drag([[-0.8, -0.6], [-0.3, -0.45], [0.3, -0.5], [0.8, -0.6]]));
  const elements = (await d.scene()).scene.elements;
  check(elements.length === 3 && elements[2].kind === "regular" && elements[2].pathline.length >= 2, "the pathline is a regular element");
  check(elements[2].pathline[0][2] === 0 && elements[2].pathline.at(-1)[2] === 1, "the pathline spans its life span");
  await d.goto(50);
  await d.settled();
  await d.shot(a.out, "02_vortex_saddle_pathline.png");

  // Select, drag and delete: a source placed, moved, removed.
  await page.selectOption("#singular-type", "source");
  await d.tool("singular");
  await d.change(() => d.click([0.5, -0.1]));
  await d.tool("select");
  await d.change(() => d.drag([[0.5, -0.1], [0.55, -0.05], [0.6, 0.0]]));
  let moved = (await d.scene()).scene.elements[3];
  check(moved?.type === "source" && Math.hypot(moved.path[0][0] - 0.6, moved.path[0][1]) < 0.02, "a dragged element moves");
  await d.change(() => page.keyboard.press("Delete"));
  check((await d.scene()).scene.elements.length === 3, "Delete removes the selected element");

  // Play the timeline.
  const before = await page.evaluate(() => window.tvf.state.frame);
  await page.click("#play");
  await page.waitForTimeout(1500);
  await page.click("#play");
  const after = await page.evaluate(() => window.tvf.state.frame);
  check(after !== before, `playing moves the time (frame ${before} → ${after})`);
  await d.shot(a.out, "03_played.png");

  // Cancel a pair at frame 50: the placed saddle and the index +1 singularity nearest to it.
  await d.goto(50);
  await d.settled();
  await d.tool("cancel");
  frame = await d.frame();
  const saddle = frame.singularities.find((s) => s.type === "saddle" && Math.hypot(s.position[0] - 0.15, s.position[1] - 0.3) < 0.1);
  const distance = (s) => Math.hypot(s.position[0] - saddle.position[0], s.position[1] - saddle.position[1]);
  const center = frame.singularities.filter((s) => s.index === 1).sort((p, q) => distance(p) - distance(q))[0];
  check(center && saddle, "the pair to cancel is at frame 50");
  await d.click(center.position);
  await d.click(saddle.position);
  await page.waitForFunction(() => !document.getElementById("message").textContent.startsWith("applying"), null, { timeout: 60000 });
  const msg = await page.textContent("#message");
  check(/cancel/i.test(msg) && !(await page.locator("#message.error").count()), `the cancel edit is applied: "${msg.trim()}"`);
  await d.settled();
  frame = await d.frame();
  const plus = ["source", "sink", "center", "repelling_focus", "attracting_focus"];
  check(nearest(frame, ["saddle"], saddle.position) > 0.05 && nearest(frame, plus, center.position) > 0.05,
    `the pair is gone at frame 50 (${center.type} at ${center.position.map((v) => v.toFixed(2))}, saddle at ${saddle.position.map((v) => v.toFixed(2))})`);
  const edited = await d.scene();
  check(edited.scene.edits.length === 1 && edited.scene.edits[0].op === "cancel", "the edit is in the scene");
  await d.shot(a.out, "04_pair_cancelled.png");

  // Reload: the same design, the same field.
  await page.reload();
  await d.settled();
  const reloaded = await d.scene();
  check(JSON.stringify(reloaded.scene) === JSON.stringify(edited.scene), "after a reload the design is intact");
  const onDisk = JSON.parse(fs.readFileSync(`${dir}/scene.json`, "utf8"));
  check(onDisk.elements.length === 3 && onDisk.edits.length === 1, "the scene file holds the design");

  // Undo the edit, then redo it.
  await d.change(() => page.click("#undo"));
  check((await d.scene()).scene.edits.length === 0, "undo drops the edit");
  await d.change(() => page.click("#redo"));
  check((await d.scene()).scene.edits.length === 1, "redo brings it back");
  await d.goto(50);
  await d.settled();
  await d.shot(a.out, "05_reloaded.png");

  // On a new design: a bifurcation inserted at t = 0.5, moved (picked in the list, clicked
  // at its new place at t = 0.6), then removed from the list: edits of the field, kept in
  // the scene. (A new one, because a design changed after an edit may no longer hold
  // what the edit names; the server then reports the failed edit.)
  await d.change(() => page.click("#new"));
  const analysis = () => page.evaluate(() => fetch("api/analysis").then((r) => r.json()));
  const creationNear = (an, x, y, t) =>
    an.bifurcations.findIndex((b) => b.kind === "creation" && Math.hypot(b.position[0] - x, b.position[1] - y) < 0.12 && Math.abs(b.t - t) < 0.06);
  const applied = async () => {
    await page.waitForFunction(() => !document.getElementById("message").textContent.startsWith("applying"), null, { timeout: 60000 });
    return { text: (await page.textContent("#message")).trim(), error: (await page.locator("#message.error").count()) > 0 };
  };
  await d.goto(50);
  await d.tool("bifurcation");
  await page.selectOption("#bifurcation-type", "saddle_sink_creation");
  await d.change(() => d.click([-0.1, -0.3]));
  let an = await analysis();
  let i = creationNear(an, -0.1, -0.3, 0.5);
  check(i >= 0, "the inserted bifurcation is in the field (a creation near (-0.1, -0.3) at t = 0.5)");
  await page.locator(`#bifurcations > div:nth-child(${i + 1}) button`, { hasText: "go to" }).click();
  await d.tool("move-bifurcation");
  await d.goto(60);
  const edits0 = (await d.scene()).scene.edits.length;
  await d.change(() => d.click([0.3, -0.3]), 60000);
  let m = await applied();
  check(!m.error && (await d.scene()).scene.edits.at(-1).op === "move_bifurcation", `the bifurcation is moved: "${m.text}"`);
  an = await analysis();
  i = creationNear(an, 0.3, -0.3, 0.6);
  check(i >= 0, "the field has the creation at its new place and time");
  await d.change(() => page.locator(`#bifurcations > div:nth-child(${i + 1}) button`, { hasText: "remove" }).click(), 60000);
  m = await applied();
  check(!m.error && (await d.scene()).scene.edits.length === edits0 + 2, `the bifurcation is removed: "${m.text}"`);
  check(creationNear(await analysis(), 0.3, -0.3, 0.6) < 0, "the field no longer has it");
  await d.shot(a.out, "06_bifurcation_edits.png");

  // Surfaces: the sphere; a click on the surface places a source there.
  await d.change(() => page.selectOption("#domain", "sphere"));
  check(await page.locator("#surface canvas").isVisible(), "the sphere is shown in 3-D");
  await d.tool("singular");
  await page.uncheck("#keyframe-mode");
  await page.selectOption("#singular-type", "source");
  const box = await page.locator("#surface canvas").boundingBox();
  await d.change(() => page.mouse.click(box.x + box.width / 2, box.y + box.height / 2));
  const onSphere = (await d.scene()).scene;
  const p = onSphere.elements[0]?.path[0];
  check(p && p.length === 4 && Math.abs(Math.hypot(p[0], p[1], p[2]) - 1) < 0.05, `a source picked on the sphere at (${p?.slice(0, 3).map((v) => v.toFixed(2))})`);
  frame = await d.frame();
  const nearSource = frame.singularities.some((s) => s.type === "source" && Math.hypot(s.position[0] - p[0], s.position[1] - p[1], s.position[2] - p[2]) < 0.1);
  check(nearSource, "the field on the sphere has a source there");
  await d.shot(a.out, "07_sphere.png");

  // An uploaded mesh: a bumpy 12 × 12 patch as OBJ.
  let obj = "";
  for (let j = 0; j < 12; ++j)
    for (let i = 0; i < 12; ++i) obj += `v ${i / 11} ${j / 11} ${(0.1 * Math.sin(3 * i / 11) * Math.cos(2 * j / 11)).toFixed(5)}\n`;
  for (let j = 0; j + 1 < 12; ++j)
    for (let i = 0; i + 1 < 12; ++i) {
      const v = j * 12 + i + 1;
      obj += `f ${v} ${v + 1} ${v + 13}\nf ${v} ${v + 13} ${v + 12}\n`;
    }
  await d.change(() => page.setInputFiles("#upload", { name: "patch.obj", mimeType: "model/obj", buffer: Buffer.from(obj) }));
  const uploaded = (await d.scene()).scene;
  const meshData = await page.evaluate(() => fetch("api/mesh").then((r) => r.json()));
  check(uploaded.domain.mesh === "patch.obj" && fs.existsSync(`${dir}/patch.obj`) && meshData.vertices.length === 144 * 3,
    "an uploaded OBJ becomes the domain (144 vertices, stored in the working folder)");
  await d.shot(a.out, "08_uploaded_mesh.png");
  check(errors.length === 0, `no errors in the page${errors.length ? ": " + errors.join("; ") : ""}`);
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
