// The page's statuses in the order the server made them (issue 15): the page hears of the
// server's state from two sources, the event stream (GET /api/events) and polls of
// GET /api/status (while a solve runs, for its progress). A poll's answer can arrive after
// newer pushed events: made before them, it waited for a core or a connection. Taken in
// the order they arrived, such an answer replaced the newer event waiting to be shown (the
// one saying that the analysis was ready, say), and the page showed the older state and
// waited for an analysis that it had been told of (with `tvf serve --solve-while-saving`
// the page often did). Here the page's polls are held back while a change is solved and
// shown (their answers made when asked, as the server made them), then delivered late,
// after the pushed events: the page must not go back to them. Each status carries the
// server's `sequence`; an older one is dropped.
// Usage: node e2e/status_order.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH] [--serve "OPTIONS"]
import path from "node:path";
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-status-order-");
// The server's status, asked by this script (not through the page, whose polls are held).
const serverStatus = () => fetch(new URL("api/status", server.url)).then((r) => r.json());
let failed = false;
let page;
try {
  page = await (await browser.newContext({ viewport: { width: 1280, height: 860 } })).newPage();
  // The page's polls, while `holding`: answered by the server at once (route.fetch), the
  // answer handed to the page only when released.
  let holding = false;
  const held = [];
  // An answer that already tells the final state of the change (its result and analysis
  // ready) is handed over at once: only those made before the last event are held, so
  // every held answer is older than what the pushed events then show.
  await page.route("**/api/status", async (route) => {
    if (!holding) return route.continue();
    const response = await route.fetch();
    const status = await response.json();
    if (status.state === "ready" && status.result_revision === status.revision && status.analysis_revision === status.revision)
      return route.fulfill({ response });
    held.push({ route, response, status });
  });
  const d = await Designer.open(page, server.url);
  // The per-frame constrained generator on New's 65² design with 250 frames: a solve long
  // enough (about a second) that the page polls for its progress meanwhile.
  await d.change(() => page.click("#new"));
  const scene = (await d.scene()).scene;
  scene.generator = "constrained";
  scene.time.frames = 250;
  await d.applyScene(scene);
  await d.tool("singular");
  await page.uncheck("#keyframe-mode");
  await page.selectOption("#singular-type", "source");

  // Changes (each adds a source) until the page polled while one was solved and shown (a
  // held answer keeps the page's polling waiting: one at most per change). The bound on the
  // wait is wide: under AddressSanitizer the analysis of the 250 frames takes a minute or
  // two on a loaded 2-core machine.
  const describe = (st) => `sequence ${st.sequence}: revision ${st.revision} ${st.state}, result ${st.result_revision}, analysis ${st.analysis_revision}`;
  let shown;
  for (let k = 0; k < 6 && !held.length; ++k) {
    const before = (await serverStatus()).revision;
    holding = true;
    await d.click([-0.6 + 0.25 * k, k % 2 ? 0.45 : -0.45]);
    // Shown by the pushed events alone: the new result, its frame and its analysis.
    await page.waitForFunction(
      (rev) => {
        const s = window.tvf.state;
        return s.resultRevision > rev && s.frames.has(s.frame) && s.analysisRevision === s.resultRevision;
      },
      before,
      { timeout: 300000, polling: 10 },
    );
    holding = false;
    shown = await page.evaluate(() => window.tvf.pending().lastStatus);
  }
  check(held.length > 0, `the page polled while a change was solved and shown (held back: ${held.map((h) => describe(h.status)).join("; ")})`);
  check(shown.state === "ready" && shown.result_revision === shown.revision && held.every((h) => h.status.sequence < shown.sequence),
        `the page showed the newer pushed status (${describe(shown)}) before the held answers`);

  // The held answers delivered now, after the newer events: the page stays where it is.
  // Watched every few ms in the page while they arrive and after.
  await page.evaluate(() => {
    const w = (window.__statusWatch = { states: [], sequences: [] });
    const t0 = performance.now();
    const look = () => {
      const st = window.tvf.pending().lastStatus;
      w.states.push(`${st.revision} ${st.state} result ${st.result_revision}`);
      w.sequences.push(st.sequence);
      if (performance.now() - t0 < 1500) setTimeout(look, 2);
    };
    look();
  });
  for (const h of held) await h.route.fulfill({ response: h.response });
  await page.waitForTimeout(1600);
  const watch = await page.evaluate(() => window.__statusWatch);
  const state = await page.evaluate(() => ({ result: window.tvf.state.resultRevision, analysis: window.tvf.state.analysisRevision }));
  check(watch.sequences.every((q) => q >= shown.sequence),
        `the page did not go back to an older status after the late answers (seen: ${[...new Set(watch.states)].join("; ")}; sequences ${[...new Set(watch.sequences)].join(", ")})`);
  const now = await serverStatus();
  check(state.result === now.result_revision && state.analysis === now.result_revision && now.state === "ready",
        `the page holds the server's newest result and its analysis (revision ${now.result_revision})`);
  check((await page.textContent("#status")).includes("ready"), "its status line says ready");
  await d.shot(a.out, "status_order.png");
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, path.join(a.out, "status_order_failure.png"));
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
