// End-to-end test of an error's place (issue 18): a scene applied from the JSON editor
// with a bad value is refused, the message line says why, and the value the error names
// (the server's json_path) is selected in the editor; on a sphere, a sketched streakline that
// crosses itself the same. Screenshots to --out.
// Usage: node e2e/error_place.e2e.mjs --tvf PATH/TO/tvf [--out DIR] [--chromium PATH]
import { check, Designer, finish, reportFailure, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-e2e-error-place-");
let failed = false;
let page;
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 860 } });
  page = await context.newPage();
  const D = await Designer.open(page, server.url);
  const text = JSON.stringify(
    { tvf: 1, domain: { grid: { size: [33, 33] } }, time: { frames: 10 },
      elements: [{ kind: "singular", type: "sourse", path: [[0, 0, 0]] }] },
    null, 2);
  await page.fill("#scene-json", text);
  await page.click("#apply-json");
  await page.waitForFunction(() => document.querySelector("#message")?.classList.contains("error"));
  const message = await page.textContent("#message");
  check(/elements\[0\]\.type/.test(message ?? ""), `the message names the key: ${message}`);
  const selected = await page.evaluate(() => {
    const t = document.querySelector("#scene-json");
    return t.value.slice(t.selectionStart, t.selectionEnd);
  });
  check(selected === '"sourse"', `the bad value is selected in the scene JSON, got ${JSON.stringify(selected)}`);
  await D.shot(a.out, "error_place.png");
  console.log("error place: ok");

  // On a surface the reader cannot test a sketched streakline (it is known only once
  // snapped onto the surface); the server, holding the domain its last solve built, refuses
  // one that crosses itself as the reader refuses it on a grid: the scene and its field kept.
  await D.applyScene({ tvf: 1, domain: { sphere: { subdivisions: 3 } }, time: { frames: 5 }, generator: "constrained",
                       elements: [{ kind: "singular", type: "ccw_center", path: [[0, 0, 1, 0]] }] });
  const before = await D.status();
  const at = (lon, lat) => {
    const [u, v] = [(lon * Math.PI) / 180, (lat * Math.PI) / 180];
    return [Math.cos(v) * Math.cos(u), Math.cos(v) * Math.sin(u), Math.sin(v)].map((c) => Number(c.toFixed(6)));
  };
  const crossing = (await D.scene()).scene;
  crossing.elements.push({ kind: "streakline", t: 0.8, from: 0.2, points: [at(0, 0), at(40, 30), at(40, 0), at(0, 30)] });
  await page.evaluate(() => document.querySelector("#message")?.classList.remove("error"));
  await page.fill("#scene-json", JSON.stringify(crossing, null, 2));
  await page.click("#apply-json");
  await page.waitForFunction(() => document.querySelector("#message")?.classList.contains("error"));
  const said = await page.textContent("#message");
  check(/elements\[1\]\.points/.test(said ?? "") && /crosses or folds back onto itself on the surface/.test(said ?? ""),
        `the message names the sketch: ${said}`);
  const chosen = await page.evaluate(() => {
    const t = document.querySelector("#scene-json");
    return t.value.slice(t.selectionStart, t.selectionEnd);
  });
  check(chosen.startsWith("[") && JSON.stringify(JSON.parse(chosen)) === JSON.stringify(crossing.elements[1].points),
        `the sketch's points are selected in the scene JSON, got ${JSON.stringify(chosen.slice(0, 80))}`);
  const after = await D.status();
  check(after.revision === before.revision && after.state === "ready",
        `the scene is kept: revision ${before.revision} → ${after.revision}, state ${after.state}`);
  await D.shot(a.out, "error_place_surface.png");
  console.log("surface sketch refused in place: ok");
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, `${a.out}/error_place_failure.png`);
}
await finish(browser, server, dir);
process.exit(failed ? 1 : 0);
