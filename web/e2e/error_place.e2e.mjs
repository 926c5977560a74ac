// End-to-end test of an error's place (issue 18): a scene applied from the JSON editor
// with a bad value is refused, the message line says why, and the value the error names
// (the server's json_path) is selected in the editor. Screenshot to --out.
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
} catch (e) {
  failed = true;
  await reportFailure(e, page, server, `${a.out}/error_place_failure.png`);
}
await finish(browser, server, dir);
process.exit(failed ? 1 : 0);
