// The deformation tools (paper §7) in the designer: a streamline of a vortex-and-saddle
// design dragged to a new place by the last frame (Fig. 12), and the whole field of a
// source turned by π over time (Fig. 10: source → center → sink).
// Usage: node e2e/deform.e2e.mjs --tvf PATH/TO/tvf [--out DIR]
import { check, Designer, finish, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-deform-");
let failed = false;
let page;
try {
  page = await browser.newPage({ viewport: { width: 1280, height: 860 } });
  const d = await Designer.open(page, server.url);
  await d.change(() => page.click("#new"));
  await d.tool("singular");
  await page.selectOption("#singular-type", "ccw_center");
  await d.change(() => d.click([-0.45, 0.1]));
  await page.selectOption("#singular-type", "saddle");
  await d.change(() => d.click([0.45, 0.1]));
  await d.goto(99);
  await d.tool("deform");
  await page.fill("#deform-turn", "0.8");
  await d.change(() => d.drag([[0, 0.6], [0, 0.5], [0, 0.4]]), 60000);
  const s = (await d.scene()).scene;
  check(s.generator === "deform" && s.deform.base.elements.length === 2 && s.deform.streamlines.length === 1, "a deformed streamline over the base design");
  check(s.deform.streamlines[0].keys[0].rotate === 0.8 && Math.abs(s.deform.streamlines[0].keys[0].translate[1] + 0.2) < 0.02, "moved by the drag, turned by 0.8");
  await d.shot(a.out, "deform_streamline_99.png");

  await d.change(() => page.click("#new"));
  await d.tool("singular");
  await page.selectOption("#singular-type", "source");
  await d.change(() => d.click([0, 0]));
  await d.change(() => page.click("#rotate-field"), 60000);
  const types = async (j) => {
    await d.goto(j);
    await d.settled();
    return (await d.frame()).singularities.filter((x) => Math.hypot(x.position[0], x.position[1]) < 0.1).map((x) => x.type);
  };
  const first = await types(0);
  const middle = await types(50);
  const last = await types(99);
  check(first.includes("source") && last.includes("sink"), `a source turned by π becomes a sink (${first} → ${middle} → ${last})`);
  await d.goto(50);
  await d.settled();
  await d.shot(a.out, "deform_rotate_50.png");
} catch (e) {
  failed = true;
  console.error(e.message);
  if (page) await page.screenshot({ path: `${a.out}/failure.png` }).catch(() => {});
  console.error(server.output());
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
