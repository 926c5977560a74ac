// Topology between key frames in the designer (issue 20, DESIGN §12): two sources in each of
// two key frames, linked crosswise with the Link key frames tool (the nearest match would
// carry each straight up), and "keep topology between key frames". The scene gets
// solver.keyframe_topology "matched" and the two links, the page says per interval whether
// it was guided, and the field's analysis has no bifurcation (free: the solve alone fades
// the sources out and in). Then the checkbox off drops the links with "matched". On a sphere
// the same by clicks on the surface: the guide leaves one source turning, which the
// interval's line counts and a warning names; "add this key frame" inserts the key frame the
// engine offers and then none turns; none with example 26's key frame half-way. A knot the
// surface guide's check turns down: "show where" rings the place of its first wrong frame.
// Usage: node e2e/keyframe_topology.e2e.mjs --tvf PATH/TO/tvf [--out DIR]
import { readFileSync } from "node:fs";
import { check, Designer, finish, start } from "./harness.mjs";

const { a, dir, browser, server } = await start("tvf-keyframe-topology-");
let failed = false;
let page;
try {
  page = await browser.newPage({ viewport: { width: 1280, height: 860 } });
  const d = await Designer.open(page, server.url);
  await d.change(() => page.click("#new"));
  await page.check("#keyframe-mode");
  await d.tool("singular");
  await page.selectOption("#singular-type", "source");
  await d.change(() => d.click([-0.5, -0.2]));
  await d.change(() => d.click([0.5, -0.2]));
  const last = (await d.scene()).scene.time.frames - 1;
  await d.goto(last);
  await d.change(() => d.click([-0.5, 0.4]));
  await d.change(() => d.click([0.5, 0.4]));
  const free = await d.settled();
  const freeAnalysis = await page.evaluate(() => window.tvf.state.analysis);
  check(!free.keyframe_intervals, "no interval report while the topology is left to the solve");

  // Linked crosswise: the right source of the last key frame is the left one's, and back.
  await d.tool("link");
  await d.click([0.5, 0.4]);
  check((await page.textContent("#message")).includes("picked"), "the first pick is said");
  await d.goto(0);
  await d.change(() => d.click([-0.5, -0.2]));
  await d.goto(last);
  await d.click([-0.5, 0.4]);
  await d.goto(0);
  const st = await d.change(() => d.click([0.5, -0.2]));
  const s = (await d.scene()).scene;
  check(s.solver?.keyframe_topology === "matched", "linking turns the topology between key frames on");
  const links = JSON.stringify(s.solver?.links);
  check(
    links === JSON.stringify([{ from: [0, 0], to: [1, 1] }, { from: [0, 1], to: [1, 0] }]),
    `the two links, crosswise (${links})`,
  );
  check(await page.isChecked("#keep-topology"), "the checkbox shows it");
  const report = await page.textContent("#keyframe-report");
  check(st.keyframe_intervals?.length === 1 && st.keyframe_intervals[0].linked === 2, "the status has the interval, 2 linked");
  check(/key frames 0 → 1: \d+ carried \(2 linked\)/.test(report), `the page says the interval: ${report}`);
  const guided = st.keyframe_intervals[0].guided;
  check(guided ? report.includes("guided") : report.includes("not guided"), "and whether it was guided");
  const analysis = await page.evaluate(() => window.tvf.state.analysis);
  console.log(
    `crosswise links: ${guided ? "guided" : `not guided: ${st.keyframe_intervals[0].unguided_reason}`}; ` +
      `bifurcations ${freeAnalysis.bifurcations.length} free → ${analysis.bifurcations.length} matched`,
  );
  check(guided && analysis.bifurcations.length === 0, "guided, and the analysis finds no bifurcation");
  await d.goto(Math.round(last / 2));
  await d.settled();
  await d.shot(a.out, "keyframe_topology_linked.png");
  await d.goto(0);
  await d.settled();
  await d.shot(a.out, "keyframe_topology_links_at_key_frame.png");

  // Off again: "matched" and its links go.
  await d.change(() => page.click("#keep-topology"));
  const off = (await d.scene()).scene;
  check(off.solver?.keyframe_topology === undefined && off.solver?.links === undefined, "unchecked: the keys are gone");
  check(await page.isHidden("#keyframe-report"), "and so is the interval report");

  // The same on the sphere, picked on the surface: two sources in each key frame on the
  // side the camera faces, linked crosswise.
  await d.change(() => page.selectOption("#domain", "sphere"));
  const unit = (v) => v.map((x) => x / Math.hypot(...v));
  const ends = {
    a0: unit([-0.35, -1, 0.25]),
    b0: unit([0.35, -1, 0.25]),
    a1: unit([-0.35, -1, -0.25]),
    b1: unit([0.35, -1, -0.25]),
  };
  const round = (v) => v.map((x) => Number(x.toFixed(4)));
  await d.editScene((sc) => {
    sc.time.frames = 48;
    sc.keyframes = [
      { t: 0, elements: [ends.a0, ends.b0].map((at) => ({ kind: "singular", type: "source", at: round(at) })) },
      { t: 1, elements: [ends.a1, ends.b1].map((at) => ({ kind: "singular", type: "source", at: round(at) })) },
    ];
  });
  check(await page.locator("#surface canvas").isVisible(), "the sphere is shown");
  const clickOnSurface = (p) => d.clickSurface(p);
  await d.goto(0);
  await d.settled();
  await clickOnSurface(ends.a0);
  check((await page.textContent("#message")).includes("keyframes[0].elements[0] picked"), "picked on the surface");
  await d.goto(47);
  await d.settled();
  await d.change(() => clickOnSurface(ends.b1));
  await clickOnSurface(ends.a1);
  await d.goto(0);
  await d.settled();
  const sphere = await d.change(() => clickOnSurface(ends.b0));
  const sl = JSON.stringify((await d.scene()).scene.solver?.links);
  check(sl === JSON.stringify([{ from: [0, 0], to: [1, 1] }, { from: [0, 1], to: [1, 0] }]), `linked crosswise on the sphere (${sl})`);
  const k = sphere.keyframe_intervals?.[0];
  const sphereReport = await page.textContent("#keyframe-report");
  check(k && k.linked === 2 && /key frames 0 → 1: \d+ carried \(2 linked\)/.test(sphereReport), `the sphere's interval said: ${sphereReport}`);
  const sphereAnalysis = await page.evaluate(() => window.tvf.state.analysis);
  console.log(`sphere, crosswise links: ${k.guided ? "guided" : `not guided: ${k.unguided_reason}`}; ${sphereAnalysis.bifurcations.length} bifurcations`);
  check(k.guided && sphereAnalysis.bifurcations.length === 0, "guided on the sphere too, no bifurcation");
  await d.shot(a.out, "keyframe_topology_sphere_links.png");
  // Two sources trading places: the guide leaves one turning a whole turn (the key frames
  // set it, as on example 26's sphere knot): the line counts it and the warning under it
  // names it. With a key frame half-way (example 26's knot_sphere_middle.json) neither is
  // shown. (The sphere knot itself takes 90 s under the sanitizers; the session test has it.)
  const linkWarnings = (await page.locator("#warnings").isVisible()) ? await page.textContent("#warnings") : "";
  check(sphereReport.includes("1 node turning a whole turn (a key frame between the two can hold it)"), "a node left turning is counted");
  check(/^warning: between keyframes\[0\] and keyframes\[1\] the source carried from .* turns 1 whole turn/.test(linkWarnings), `and named: ${linkWarnings}`);
  // "add this key frame": the key frame the engine offers (the two sources where the plan
  // carries them half-way) inserted, both links kept through it; no node turns then.
  const offered = k.middle_keyframe;
  check(offered && offered.keyframe.elements.length === 2, `the status offers a key frame: ${JSON.stringify(offered)}`);
  const add = page.locator("#keyframe-report button.add-middle-keyframe");
  check((await add.count()) === 1, "the line has \"add this key frame\"");
  // Under the sanitizers (--no-added-solve) it is not clicked: the three-key-frame sphere's
  // solve takes 2.5 minutes there (6 s in a release build), more than the test can wait on
  // top of the rest (a newer scene would stop it at once: the plan has checkpoints since
  // session 40). The engine's side runs under them in the CLI test
  // Example26KnotOnASphereIsGuided, the insertion in the web unit tests.
  if (!process.argv.includes("--no-added-solve")) {
    const added = await d.change(() => add.click(), 300000);
    const withMiddle = (await d.scene()).scene;
    check(withMiddle.keyframes.length === 3 && Math.abs(withMiddle.keyframes[1].t - offered.keyframe.t) < 1e-12, "the key frame is inserted");
    const throughLinks = JSON.stringify(withMiddle.solver?.links);
    check(
      throughLinks === JSON.stringify([{ from: [0, 0], to: [1, 0] }, { from: [1, 0], to: [2, 1] }, { from: [0, 1], to: [1, 1] }, { from: [1, 1], to: [2, 0] }]),
      `both links kept through it (${throughLinks})`,
    );
    const addedReport = await page.textContent("#keyframe-report");
    const addedWarnings = (await page.locator("#warnings").isVisible()) ? await page.textContent("#warnings") : "";
    console.log(`added the offered key frame: ${addedReport}`);
    check(added.keyframe_intervals?.length === 2 && added.keyframe_intervals.every((i) => i.guided && !i.turning), "both intervals guided, no node turning");
    check(!addedReport.includes("turning") && addedWarnings === "", `no node turns, no warning (${addedWarnings})`);
    await d.shot(a.out, "keyframe_topology_sphere_added_keyframe.png");
  }
  const example = (name) => JSON.parse(readFileSync(new URL(`../../examples/26_keyframe_topology/${name}`, import.meta.url), "utf8"));
  await d.applyScene(example("knot_sphere_middle.json"));
  const middle = await page.textContent("#keyframe-report");
  check(/key frames 1 → 2: 4 carried/.test(middle), `the knot with a key frame half-way: ${middle}`);
  check(!middle.includes("turning") && (await page.locator("#warnings").isHidden()), "no node turns, no warning");
  await d.shot(a.out, "keyframe_topology_sphere_middle.png");

  // An interval the surface guide's check turns down (the knot of the C++ test
  // AGuideRejectedAtEveryTryCountsAllItsWrongFrames: a source and a center trading places on
  // the 42-vertex sphere): its line says why and has "show where", which goes to the first
  // wrong frame, turns the camera to the place and rings it; "hide" takes the ring away.
  const z = Math.sqrt(0.75);
  const knot = (first, second) => [
    { kind: "singular", type: "source", at: first },
    { kind: "singular", type: "ccw_center", at: second },
  ];
  const rejected = await d.applyScene({
    tvf: 1,
    domain: { sphere: { subdivisions: 1, radius: 1 } },
    time: { frames: 32, range: [0, 1] },
    generator: "spacetime",
    falloff: 8,
    solver: { region_radius: 0.15, keyframe_topology: "matched" },
    keyframes: [
      { t: 0, elements: knot([-0.5, 0, z], [0.5, 0, z]) },
      { t: 1, elements: knot([0.5, 0, z], [-0.5, 0, z]) },
    ],
  });
  const w = rejected.keyframe_intervals?.[0]?.first_wrong;
  const rejectedReport = await page.textContent("#keyframe-report");
  check(w && !rejected.keyframe_intervals[0].guided, `the guide is turned down, its first wrong frame in the status: ${rejectedReport}`);
  check(rejectedReport.includes(`not guided, left free (key frames only): the surface guide's frames hold other singularities`), "the line says why");
  const show = page.locator("#keyframe-report button.show-wrong");
  check((await show.textContent()) === "show where", "and offers to show where");
  // Pixels of the ring's colour (#06b6d4) in a box around the place on the picture: on the
  // surface 40 CSS pixels either side of `at`, on the plane ("field") 30 canvas pixels.
  const ringPixels = (at = w.at, view = "surface") =>
    page.evaluate(
      async ([p, flat]) => {
        await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
        const { data, width, height, scale } = window.tvf.pixels(flat ? "field" : "surface");
        // The plane's view maps to canvas pixels already; the surface's to CSS pixels.
        const [x, y] = (flat ? window.tvf.view().toCanvas(p) : window.tvf.surface(p).map((v) => v * scale)).map(Math.round);
        const half = flat ? 30 : Math.round(40 * scale);
        let n = 0;
        for (let v = Math.max(0, y - half); v < Math.min(height, y + half); ++v)
          for (let u = Math.max(0, x - half); u < Math.min(width, x + half); ++u) {
            const i = 4 * (v * width + u);
            if (Math.abs(data[i] - 6) < 30 && Math.abs(data[i + 1] - 182) < 30 && Math.abs(data[i + 2] - 212) < 30) ++n;
          }
        return n;
      },
      [at, view === "field"],
    );
  const before = await ringPixels();
  await show.click();
  const frameWanted = Math.round(w.t * 31);
  await page.waitForFunction((j) => window.tvf.state.frame === j, frameWanted);
  await d.settled();
  const after = await ringPixels();
  const seen = await page.evaluate((p) => window.tvf.surfaceVisible(p), w.at);
  console.log(`first wrong frame t = ${w.t.toFixed(3)} (frame ${frameWanted}), ${w.extra ? "an extra" : "a missing"} ${w.type}; ring pixels ${before} → ${after}`);
  check(seen, "the camera turned to the place: it is seen");
  check(before === 0 && after > 50, `and it is ringed (${before} → ${after} pixels of the ring's colour)`);
  check((await show.textContent()) === "hide", "the button now hides it");
  await d.shot(a.out, "keyframe_topology_show_where.png");
  await show.click();
  check((await ringPixels()) === 0 && (await show.textContent()) === "show where", "hidden again");

  // Two paths that cannot be kept apart (a source and a sink trading places on the
  // 162-vertex sphere, asked to keep 1.5 apart): the line names the collision and "show
  // where" goes to the frame where they come closest and rings both.
  const pair = (first, second) => [
    { kind: "singular", type: "source", at: first },
    { kind: "singular", type: "sink", at: second },
  ];
  const collided = await d.applyScene({
    tvf: 1,
    domain: { sphere: { subdivisions: 2, radius: 1 } },
    time: { frames: 16, range: [0, 1] },
    generator: "spacetime",
    falloff: 8,
    solver: { region_radius: 0.15, keyframe_topology: "matched", path_separation: 1.5 },
    keyframes: [
      { t: 0, elements: pair([-0.5, 0, z], [0.5, 0, z]) },
      { t: 1, elements: pair([0.5, 0, z], [-0.5, 0, z]) },
    ],
  });
  const c = collided.keyframe_intervals?.[0]?.collision_at;
  const collidedReport = await page.textContent("#keyframe-report");
  check(c && c.types.join(" ") === "source sink" && c.t === 0.5, `the collision's place in the status: ${JSON.stringify(c)}`);
  check(collidedReport.includes("two of its paths could not be kept apart"), `the line says why: ${collidedReport}`);
  check((await show.count()) === 1, "and offers to show where");
  await show.click();
  await page.waitForFunction((j) => window.tvf.state.frame === j, 8);
  await d.settled();
  const ringed = await ringPixels(c.points[0]);
  check(await page.evaluate((ps) => ps.every((p) => window.tvf.surfaceVisible(p)), c.points), "the camera turned to the two: both are seen");
  check(ringed > 50, `and they are ringed (${ringed} pixels of the ring's colour)`);
  await d.shot(a.out, "keyframe_topology_show_collision.png");

  // The same on the plane (the C++ test CrossingPathsWithNoRoomAreReported: a strip too
  // narrow to pass the separation asked): "show where" rings the two on the picture.
  const strip = await d.applyScene({
    tvf: 1,
    domain: { grid: { size: [65, 9], min: [-1, -0.125], max: [1, 0.125] } },
    time: { frames: 17, range: [0, 1] },
    generator: "spacetime",
    falloff: 8,
    solver: { region_radius: 0.1, keyframe_topology: "matched", path_separation: 0.2 },
    keyframes: [
      { t: 0, elements: pair([-0.5, 0], [0.5, 0]) },
      { t: 1, elements: pair([0.5, 0], [-0.5, 0]) },
    ],
  });
  const sc = strip.keyframe_intervals?.[0]?.collision_at;
  check(sc && sc.t === 0.5, `the strip's collision in the status: ${JSON.stringify(sc)}`);
  const planeRing = () => ringPixels(sc.points[0].slice(0, 2), "field");
  const planeBefore = await planeRing();
  check((await show.count()) === 1, "the strip's line offers to show where");
  await show.click();
  await page.waitForFunction((j) => window.tvf.state.frame === j, 8);
  await d.settled();
  const planeAfter = await planeRing();
  check(planeBefore === 0 && planeAfter > 30, `and rings them on the plane (${planeBefore} → ${planeAfter} pixels of the ring's colour)`);
  await d.shot(a.out, "keyframe_topology_show_collision_plane.png");
} catch (e) {
  failed = true;
  console.error(e.message);
  if (page) await page.screenshot({ path: `${a.out}/failure.png` }).catch(() => {});
  console.error(server.output());
} finally {
  await finish(browser, server, dir);
}
process.exit(failed ? 1 : 0);
