// End-to-end test of two tabs on one design (issue 16, item 7): every change names the
// revision it was made on; a tab that has not seen the other's change gets 412 from the
// server and applies its change again on top of the other's, saying so; quick clicks in
// one tab build on each other. Nothing is lost. Also: the space-time view's time axis
// is labelled. Screenshots of both tabs go to --out.
// Usage: node e2e/tabs.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-tabs-");
let failed = false;
let pageA;
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 860 } });
  const errors = [];
  pageA = await context.newPage();
  const pageB = await context.newPage();
  for (const p of [pageA, pageB]) p.on("pageerror", (e) => errors.push(e.message));
  const A = await Designer.open(pageA, server.url);
  await A.change(() => pageA.click("#new"));
  // Tab B runs on the polling fallback (its event stream refused, as behind a proxy that
  // cuts streams), so that its polling can be held back below; tab A uses the stream.
  await pageB.route("**/api/events", (route) => route.abort());
  const B = await Designer.open(pageB, server.url);
  const types = async () => (await A.scene()).scene.elements.map((e) => e.type);

  // Tab B goes stale: its polling is held back, so it does not see A's change.
  let release;
  const held = new Promise((r) => (release = r));
  await pageB.route("**/api/status", async (route) => {
    await held;
    await route.continue().catch(() => {});
  });
  const staleRevision = await pageB.evaluate(() => window.tvf.state.scene.revision);

  // Tab A places a sink.
  await A.tool("singular");
  await pageA.uncheck("#keyframe-mode");
  await pageA.selectOption("#singular-type", "sink");
  await A.change(() => A.click([0.4, 0.3]));
  check(JSON.stringify(await types()) === JSON.stringify(["sink"]), "tab A's sink is in the scene");

  // Tab B, still on the old revision, places a saddle: refused (412), then applied on
  // top of A's sink, and the page says so.
  check((await pageB.evaluate(() => window.tvf.state.scene.revision)) === staleRevision, `tab B is stale (revision ${staleRevision})`);
  await B.tool("singular");
  await pageB.uncheck("#keyframe-mode");
  await pageB.selectOption("#singular-type", "saddle");
  const responses = [];
  pageB.on("response", (r) => {
    if (r.url().endsWith("/api/scene") && r.request().method() === "PUT") responses.push(r.status());
  });
  await B.click([-0.4, 0.3]);
  await pageB.waitForFunction(() => /on top/.test(document.getElementById("message").textContent), null, { timeout: 20000 });
  const messageB = (await pageB.textContent("#message")).trim();
  check(responses[0] === 412 && responses.at(-1) === 200, `tab B's stale change got 412, then went through on top (${responses.join(", ")})`);
  check(/another tab/.test(messageB), `tab B says what happened: "${messageB}"`);
  check(JSON.stringify(await types()) === JSON.stringify(["sink", "saddle"]), "both the sink and the saddle are in the scene");
  release();
  await pageB.unroute("**/api/status");

  // Four quick clicks in tab A (sources), each before the answer to the one before: all
  // four reach the scene.
  await A.settled();
  await pageA.selectOption("#singular-type", "source");
  const before = (await A.scene()).revision;
  const points = [[-0.6, -0.5], [-0.2, -0.5], [0.2, -0.5], [0.6, -0.5]];
  const pixels = [];
  for (const p of points) pixels.push(await A.at(p));
  // Each answer to a PUT held back 250 ms in the browser (the server has it at once): on a
  // quiet machine the server answers within the clicks' 5 ms, and the clicks must come
  // before the answers to the changes before them, whatever the machine's speed.
  const holdPuts = async (route) => {
    if (route.request().method() !== "PUT") return route.continue();
    const response = await route.fetch();
    await new Promise((r) => setTimeout(r, 250));
    await route.fulfill({ response });
  };
  await pageA.route("**/api/scene", holdPuts);
  let putsAnswered = 0;
  pageA.on("response", (r) => {
    if (r.url().endsWith("/api/scene") && r.request().method() === "PUT") ++putsAnswered;
  });
  // Dispatched in the page, 5 ms apart (Playwright's own clicks take longer than that).
  const clickMs = await pageA.evaluate(async (pts) => {
    const c = document.getElementById("field");
    c.setPointerCapture = () => {}; // synthetic pointers cannot be captured
    window.tvf.preview?.pause(true); // the moving preview's ticks would space the clicks out
    const t0 = performance.now();
    for (const [x, y] of pts) {
      const o = { clientX: x, clientY: y, pointerId: 1, pointerType: "mouse", isPrimary: true, button: 0, bubbles: true };
      c.dispatchEvent(new PointerEvent("pointerdown", o));
      c.dispatchEvent(new PointerEvent("pointerup", o));
      await new Promise((r) => setTimeout(r, 5));
    }
    return Math.round(performance.now() - t0);
  }, pixels);
  const answeredDuringClicks = putsAnswered;
  check(answeredDuringClicks < 3, `the clicks came before the answers to the changes before them (${answeredDuringClicks} of 4 answered meanwhile)`);
  const deadline = Date.now() + 30000;
  while (((await A.scene()).revision < before + 4 || putsAnswered < 4) && Date.now() < deadline) await pageA.waitForTimeout(50);
  await pageA.unroute("**/api/scene", holdPuts);
  const after = (await A.scene()).scene.elements;
  const sources = after.filter((e) => e.type === "source").map((e) => e.path[0].slice(0, 2));
  check(sources.length === 4 && points.every((p) => sources.some((q) => Math.hypot(q[0] - p[0], q[1] - p[1]) < 0.03)),
    `four clicks in ${clickMs} ms: four sources in the scene (${sources.map((q) => `(${q.map((v) => v.toFixed(2))})`).join(" ")})`);
  check(after.length === 6, "and the sink and saddle are still there");

  // Tab B follows: it shows the same scene (polling), without a change of its own.
  await A.settled();
  await B.settled();
  const shownB = await pageB.evaluate(() => window.tvf.state.scene.scene.elements.length);
  check(shownB === 6, "tab B shows all six elements");
  const labels = await pageA.evaluate(() => window.tvf.spacetimeLabels());
  check(labels.length >= 3, `the space-time view labels its time axis (${labels.map((l) => l.t).join(", ")})`);
  await A.goto(50);
  await A.settled();
  await A.shot(a.out, "tabs_A.png");
  await B.shot(a.out, "tabs_B.png");
  check(errors.length === 0, `no errors in the pages${errors.length ? ": " + errors.join("; ") : ""}`);
} catch (e) {
  failed = true;
  await reportFailure(e, pageA, server, `${a.out}/tabs_failure.png`);
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
