// The CPU the browser spends on the moving texture of the planar view (issue 15): every
// process of its Chromium's CPU time (/proc) over 8 s with the texture moving, then held still
// (window.tvf.preview.pause), twice, on the design New makes. Prints cores in use; not a test.
// Usage: node e2e/texture_cpu.mjs --tvf PATH/TO/tvf [--chromium PATH]
import fs from "node:fs";
import { args, Designer, finish, launch, startServer, tempDir } from "./harness.mjs";
const a = args();
const dir = tempDir("tvf-cpu-");
const browser = await launch(a.chromium);
const server = await startServer(a.tvf, dir);
const page = await (await browser.newContext({ viewport: { width: 1280, height: 860 } })).newPage();
const d = await Designer.open(page, server.url);
await d.change(() => page.click("#new"));
// CPU seconds (utime + stime, /proc) of this script's browser: the processes below it.
const cpu = () => {
  const stat = new Map();
  for (const p of fs.readdirSync("/proc").filter((x) => /^\d+$/.test(x))) {
    try {
      const f = fs.readFileSync(`/proc/${p}/stat`, "utf8").split(") ")[1].split(" ");
      stat.set(Number(p), { parent: Number(f[1]), seconds: (Number(f[11]) + Number(f[12])) / 100 });
    } catch {}
  }
  const mine = new Set([process.pid]);
  for (let grew = true; grew; ) {
    grew = false;
    for (const [p, s] of stat) if (!mine.has(p) && mine.has(s.parent)) (mine.add(p), (grew = true));
  }
  let t = 0;
  for (const p of mine) if (p !== process.pid && p !== server.proc.pid) t += stat.get(p)?.seconds ?? 0;
  return t;
};
for (const paused of [false, true, false, true]) {
  await page.evaluate((on) => window.tvf.preview.pause(on), paused);
  await page.waitForTimeout(1000);
  const c0 = cpu(), t0 = Date.now();
  await page.waitForTimeout(8000);
  console.log(`${paused ? "texture still " : "texture moving"}: chromium ${((cpu() - c0) / ((Date.now() - t0) / 1000)).toFixed(2)} cores`);
}
await finish(browser, server, dir);
