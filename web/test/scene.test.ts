import { describe, expect, it } from "vitest";
import * as S from "../src/scene";
import {
  addKeyframeSingular,
  emptyScene,
  keyframeLinks,
  keyframeTopologyMatched,
  linkKeyframeElements,
  removeHandle,
  setGenerator,
  setKeyframeTopology,
  type Handle,
  type Scene,
} from "../src/scene";

describe("scene changes", () => {
  it("leave their argument unchanged and add what they say", () => {
    const s0 = S.emptyScene();
    const before = JSON.stringify(s0);
    const s1 = S.addSingular(s0, "ccw_center", [0.1, 0.2], [0.5, 0.2], 0.2, 0.8);
    expect(JSON.stringify(s0)).toBe(before);
    expect(s1.elements).toEqual([{ kind: "singular", type: "ccw_center", path: [[0.1, 0.2, 0.2], [0.5, 0.2, 0.8]] }]);
    const fixed = S.addSingular(s0, "source", [0, 0], undefined, 0);
    expect(fixed.elements![0]).toEqual({ kind: "singular", type: "source", path: [[0, 0, 0]] });
  });

  it("spread a drawn pathline evenly over its life span", () => {
    const s = S.addPathline(S.emptyScene(), [[-1, 0], [0, 0.5], [1, 0]], 0.2, 0.6);
    const e = s.elements![0] as S.RegularElement;
    const times = e.pathline.map((p) => p[2]);
    [0.2, 0.4, 0.6].forEach((t, i) => expect(times[i]).toBeCloseTo(t, 12));
    expect(e.pathline.map((p) => p.slice(0, 2))).toEqual([[-1, 0], [0, 0.5], [1, 0]]);
    expect(() => S.addPathline(S.emptyScene(), [[0, 0]], 0, 1)).toThrow(/two points/);
    expect(() => S.addPathline(S.emptyScene(), [[0, 0], [1, 1]], 0.5, 0.5)).toThrow(/end time/);
  });

  it("keep the third coordinate of points picked on a surface", () => {
    const sphere: S.Scene = { ...S.emptyScene(), domain: { sphere: { subdivisions: 4, radius: 1 } } };
    const picked = [[0, -1, 0], [0.6, -0.8, 0], [0.8, -0.6, 0]];
    const p = S.addPathline(sphere, picked, 0, 1).elements![0] as S.RegularElement;
    expect(p.pathline).toEqual([[0, -1, 0, 0], [0.6, -0.8, 0, 0.5], [0.8, -0.6, 0, 1]]);
    const k = S.addKeyframeStreamline(sphere, 0.5, picked);
    expect(k.keyframes![0].streamlines).toEqual([{ points: picked }]);
    expect(k.generator).toBe("spacetime");
  });

  it("put key-frame elements into one key frame per frame and switch to the spacetime generator", () => {
    let s = S.addKeyframeSingular(S.emptyScene(), 0, "ccw_center", [0.5, -0.5]);
    s = S.addKeyframeSingular(s, 0.001, "ccw_center", [0.5, 0.5]); // same frame of 100
    s = S.addKeyframeSingular(s, 1, "ccw_center", [0.6, 0]);
    expect(s.generator).toBe("spacetime");
    expect(s.keyframes!.map((k) => k.t)).toEqual([0, 1]);
    expect(s.keyframes![0].elements).toHaveLength(2);
    s = S.addKeyframeStreamline(s, 1, [[-1, 0], [1, 0]]);
    expect(s.keyframes![1].streamlines).toEqual([{ points: [[-1, 0], [1, 0]] }]);
  });

  it("pick, move and remove handles at the current time", () => {
    let s = S.addSingular(S.emptyScene(), "source", [-0.5, 0], [0.5, 0], 0, 1);
    s = S.addKeyframeSingular(s, 0.5, "sink", [0, 0.5]);
    expect(S.singularPosition(s.elements![0] as S.SingularElement, 0.5)).toEqual([0, 0]);
    const h = S.pick(s, 0.9, [0.4, 0.01], 0.1); // position at t = 0.9 is (0.4, 0)
    expect(h).toEqual({ kind: "element", index: 0, point: 1 });
    const moved = S.moveHandle(s, h!, [0.5, 0.4]);
    expect((moved.elements![0] as S.SingularElement).path[1]).toEqual([0.5, 0.4, 1]);
    expect(S.pick(s, 0.9, [0, 0.5], 0.1)).toBeUndefined(); // the key frame is at t = 0.5
    const k = S.pick(s, 0.5, [0, 0.5], 0.1)!;
    expect(k).toEqual({ kind: "keyframe", key: 0, index: 0 });
    expect(S.removeHandle(s, k).keyframes).toEqual([]);
    expect(S.removeHandle(s, h!).elements).toEqual([]);
  });

  it("add a sketched streakline at the current time and move its points", () => {
    const s0 = S.emptyScene();
    const s = S.addStreakline(s0, [[-0.5, -0.5], [0, -0.2], [0.5, -0.5]], 0.8);
    const [t0, t1] = s0.time?.range ?? [0, 1];
    expect(s.elements).toEqual([
      { kind: "streakline", points: [[-0.5, -0.5], [0, -0.2], [0.5, -0.5]], t: 0.8, from: Number(Math.max(t0, 0.8 - 0.5 * (t1 - t0)).toFixed(4)) },
    ]);
    expect(s.generator).toBe("spacetime");
    const h = S.pick(s, 0.8, [0, -0.2], 0.05);
    expect(h).toEqual({ kind: "element", index: 0, point: 1 });
    const moved = S.moveHandle(s, h!, [0.1, -0.1]);
    expect((moved.elements![0] as S.StreaklineElement).points[1]).toEqual([0.1, -0.1]);
    expect(() => S.addStreakline(s0, [[0, 0]], 0.8)).toThrow(/two points/);
    expect(() => S.addStreakline(s0, [[0, 0], [1, 0]], t0)).toThrow(/after the start/);
  });

  it("map times and frames both ways", () => {
    const s = S.emptyScene();
    expect(S.frameTime(s, 99)).toBe(1);
    expect(S.frameOf(s, S.frameTime(s, 37))).toBe(37);
    expect(S.frameOf(s, 7)).toBe(99);
  });

  it("write the edits of DESIGN §7", () => {
    expect(S.cancelEdit(40, [0.1, 0.2], [0.15, 0.22])).toEqual({ op: "cancel", frame: 40, pair: [[0.1, 0.2], [0.15, 0.22]] });
    expect(S.removeBifurcationEdit([0.1, 0.2], 0.5)).toEqual({ op: "remove_bifurcation", at: [0.1, 0.2, 0.5] });
    expect(S.moveBifurcationEdit([0, 0], 0.5, [0.1, 0], 0.6)).toEqual({ op: "move_bifurcation", at: [0, 0, 0.5], to: [0.1, 0, 0.6] });
  });

  it("give a bifurcation the axis and scale of a drag (its end in the chart around its start)", () => {
    expect(S.bifurcationAxis()).toEqual({ scale: 0.25, angle: 0 });
    expect(S.bifurcationAxis([0, 0.3])).toEqual({ scale: 0.3, angle: 1.571 });
    expect(S.bifurcationAxis([-0.3, -0.4])).toEqual({ scale: 0.5, angle: -2.214 });
    expect(S.bifurcationAxis([0.01, 0])).toEqual({ scale: 0.05, angle: 0 });
    const s = S.addBifurcation(S.emptyScene(), "saddle_sink_creation", [0.6, 0, 0.8], 0.4, 0.3, 1.571);
    expect(s.elements?.[0]).toEqual({ kind: "bifurcation", type: "saddle_sink_creation", at: [0.6, 0, 0.8, 0.4], scale: 0.3, time_scale: 0.25, angle: 1.571 });
  });

  it("give a clicked Hopf template seven edge lengths where 0.25 is fewer", () => {
    // Two right triangles with legs 1: edges 1, 1, √2 each.
    const h = S.meanEdgeLength([0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0], [0, 1, 2, 0, 2, 3]);
    expect(h).toBeCloseTo((2 + Math.SQRT2) / 3, 12);
    expect(S.clickedBifurcationScale("hopf_supercritical", 0.0755)).toBe(0.529); // the default sphere
    expect(S.clickedBifurcationScale("hopf_subcritical", 0.02)).toBe(0.25); // fine enough for 0.25
    expect(S.clickedBifurcationScale("saddle_sink_creation", 0.0755)).toBe(0.25);
    expect(S.bifurcationAxis(undefined, 0.529)).toEqual({ scale: 0.529, angle: 0 });
    expect(S.bifurcationAxis([0, 0.3], 0.529).scale).toBe(0.3); // a drag gives its own
  });
});

describe("deformation", () => {
  it("moves the design into the base field and keys streamlines by time", () => {
    let s = S.addSingular(S.emptyScene(), "saddle", [0.4, 0.1], undefined, 0);
    s = S.addDeformStreamline(s, [0, 0.6], [0, -0.2], 1, 0.8);
    expect(s.generator).toBe("deform");
    expect(s.elements).toEqual([]);
    const d = s.deform as S.DeformBlock;
    expect(d.base.elements).toHaveLength(1);
    expect(d.streamlines).toEqual([{ seed: [0, 0.6], keys: [{ t: 1, translate: [0, -0.2], rotate: 0.8, scale: 1 }] }]);
    s = S.addDeformStreamline(s, [0, 0.6], [0.1, 0], 0.5);
    s = S.addDeformStreamline(s, [0, 0.6], [0.2, 0], 0.5); // same frame: replaced
    expect((s.deform as S.DeformBlock).streamlines![0].keys.map((k) => k.t)).toEqual([0.5, 1]);
    expect((s.deform as S.DeformBlock).base.elements).toHaveLength(1); // kept, not nested again
    expect(() => S.addDeformStreamline(s, [0, 0], [0, 0], 0)).toThrow(/after the first frame/);
  });

  it("keys a streamline on a surface with [x, y, z] seeds and translations", () => {
    const sphere: S.Scene = { ...S.emptyScene(), domain: { sphere: { subdivisions: 4, radius: 1 } } };
    let s = S.addSingular(sphere, "ccw_center", [0, 0, 1], undefined, 0);
    expect(S.deformSeeds(s)).toEqual([]);
    s = S.addDeformStreamline(s, [0.3, 0, 0.95], [0, 0.2, 0], 1, 0.5);
    s = S.addDeformStreamline(s, [0.3, 0, 0.95], [0, 0.3, -0.01], 1); // same frame: replaced
    s = S.addDeformStreamline(s, [0, 0.3, 0.95], [0.1, 0, 0], 1); // another seed: another streamline
    const d = s.deform as S.DeformBlock;
    expect(d.base.elements).toEqual([{ kind: "singular", type: "ccw_center", path: [[0, 0, 1, 0]] }]);
    expect(d.streamlines![0]).toEqual({ seed: [0.3, 0, 0.95], keys: [{ t: 1, translate: [0, 0.3, -0.01], rotate: 0, scale: 1 }] });
    expect(S.deformSeeds(s)).toEqual([
      [0.3, 0, 0.95],
      [0, 0.3, 0.95],
    ]);
    expect(S.moveBifurcationEdit([0.6, 0, 0.8], 0.4, [0, 0.6, 0.8], 0.45)).toEqual({ op: "move_bifurcation", at: [0.6, 0, 0.8, 0.4], to: [0, 0.6, 0.8, 0.45] });
  });

  it("keys a rotation of the whole field from the first time to the last", () => {
    const s = S.setDeformTransform(S.addSingular(S.emptyScene(), "source", [0, 0], undefined, 0), Math.PI);
    expect((s.deform as S.DeformBlock).transform).toEqual([
      { t: 0, sx: 1, sy: 1, theta: 0 },
      { t: 1, sx: 1, sy: 1, theta: Math.PI },
    ]);
  });
});

describe("moving elements", () => {
  it("are drawn on the engine's Hermite path (Catmull–Rom tangents), not on straight segments", () => {
    // (0, 0) at t = 0, (1, 0) at 0.5, (1, 1) at 1: tangents (2, 0) and (1, 1) at the first
    // two points; at t = 0.25 the Hermite basis (½, ⅛, ½, −⅛) gives (0.5625, −0.0625).
    const e: S.SingularElement = { kind: "singular", type: "source", path: [[0, 0, 0], [1, 0, 0.5], [1, 1, 1]] };
    const p = S.singularPosition(e, 0.25)!;
    expect(p[0]).toBeCloseTo(0.5625, 12);
    expect(p[1]).toBeCloseTo(-0.0625, 12);
    // Through the control points, clamped to the life span, and 3-D points on surfaces.
    expect(S.singularPosition(e, 0.5)).toEqual([1, 0]);
    expect(S.singularPosition(e, 1.5)).toBeUndefined();
    expect(S.hermitePosition([[0, 0, 1, 0], [0, 1, 0, 1]], 0.5)).toEqual([0, 0.5, 0.5]);
    // Two points: a straight path at constant speed, as before.
    expect(S.hermitePosition([[0, 0, 0], [1, 2, 1]], 0.25)).toEqual([0.25, 0.5]);
  });

  it("keep the dragged curve's points, thinned, over their life span", () => {
    const s = S.addSingularPath(S.emptyScene(), "sink", [[0, 0], [0.5, 0.2], [1, 0]], 0.2, 0.6);
    expect((s.elements![0] as S.SingularElement).path).toEqual([[0, 0, 0.2], [0.5, 0.2, 0.4], [1, 0, 0.6]]);
    expect((S.addSingularPath(S.emptyScene(), "sink", [[0, 0]], 0.2, 0.6).elements![0] as S.SingularElement).path).toEqual([[0, 0, 0.2]]);
  });
});

describe("topology between key frames", () => {
  // Two key frames (t = 0 and 1) with a source and a center each.
  const two = (): Scene => {
    let s = emptyScene();
    s = addKeyframeSingular(s, 0, "source", [-0.4, -0.3]);
    s = addKeyframeSingular(s, 0, "ccw_center", [0.4, 0.3]);
    s = addKeyframeSingular(s, 1, "ccw_center", [-0.4, -0.3]);
    s = addKeyframeSingular(s, 1, "source", [0.4, 0.3]);
    return s;
  };
  const kf = (key: number, index: number): Handle => ({ kind: "keyframe", key, index });

  it("turns matched on only with two key frames, and off with every key it takes", () => {
    const one = addKeyframeSingular(emptyScene(), 0, "source", [0, 0]);
    expect(() => setKeyframeTopology(one, true)).toThrow(/two key frames at least \(the design has 1\)/);
    const s = setKeyframeTopology(two(), true);
    expect(s.solver).toEqual({ keyframe_topology: "matched" });
    expect(keyframeTopologyMatched(s)).toBe(true);
    const linked = linkKeyframeElements(s, kf(0, 0), kf(1, 1));
    expect(setKeyframeTopology(linked, false).solver).toBeUndefined();
    // Another generator cannot take "matched": changing to it drops the keys.
    expect(setGenerator(linked, "constrained").solver).toBeUndefined();
    expect(setGenerator(linked, "spacetime").solver?.links).toEqual([{ from: [0, 0], to: [1, 1] }]);
  });

  it("links a key frame's singularity with one of the same type in the next, in either order", () => {
    const s = linkKeyframeElements(two(), kf(1, 1), kf(0, 0));
    expect(s.generator).toBe("spacetime");
    expect(keyframeLinks(s)).toEqual([{ from: [0, 0], to: [1, 1] }]);
    // A new link of an element replaces its old one.
    const again = linkKeyframeElements(s, kf(0, 0), kf(1, 1));
    expect(keyframeLinks(again)).toEqual([{ from: [0, 0], to: [1, 1] }]);
    const both = linkKeyframeElements(s, kf(0, 1), kf(1, 0));
    expect(keyframeLinks(both)).toEqual([
      { from: [0, 0], to: [1, 1] },
      { from: [0, 1], to: [1, 0] },
    ]);
    // A middle key frame's element linked both ways: the chain 0 → 1 → 2 keeps both links.
    const three = addKeyframeSingular(two(), 0.5, "source", [0, 0]);
    const chain = linkKeyframeElements(linkKeyframeElements(three, kf(0, 0), kf(1, 0)), kf(1, 0), kf(2, 1));
    expect(keyframeLinks(chain)).toEqual([
      { from: [0, 0], to: [1, 0] },
      { from: [1, 0], to: [2, 1] },
    ]);
    expect(() => linkKeyframeElements(two(), kf(0, 0), kf(1, 0))).toThrow(/a source cannot be linked with a ccw_center/);
    expect(() => linkKeyframeElements(two(), kf(0, 0), kf(0, 1))).toThrow(/same key frame/);
    expect(() => linkKeyframeElements(two(), { kind: "element", index: 0, point: 0 }, kf(1, 1))).toThrow(/key-frame elements/);
  });

  it("keeps the links on their elements when key frames and elements come and go", () => {
    const s = linkKeyframeElements(linkKeyframeElements(two(), kf(0, 0), kf(1, 1)), kf(0, 1), kf(1, 0));
    // A key frame added between the two: the interval is split, the links across it dropped.
    const middle = addKeyframeSingular(s, 0.5, "sink", [0, 0]);
    expect(middle.keyframes?.map((k) => k.t)).toEqual([0, 0.5050505050505051, 1]);
    expect(keyframeLinks(middle)).toEqual([]);
    // An element added to the first key frame: the links stay where they were.
    const more = addKeyframeSingular(s, 0, "saddle", [0, 0.5]);
    expect(keyframeLinks(more)).toEqual(keyframeLinks(s));
    // The first key frame's source removed: its link goes, the center's index moves down.
    const removed = removeHandle(s, kf(0, 0));
    expect(removed.keyframes?.[0].elements?.map((e) => e.type)).toEqual(["ccw_center"]);
    expect(keyframeLinks(removed)).toEqual([{ from: [0, 0], to: [1, 0] }]);
    // A whole key frame removed: fewer than two left, so "matched" goes.
    let gone = removeHandle(s, kf(1, 0));
    gone = removeHandle(gone, kf(1, 0));
    expect(gone.keyframes?.length).toBe(1);
    expect(gone.solver).toBeUndefined();
  });

  it("inserts the key frame the engine offers, each link kept through it", () => {
    // The source linked crosswise (0,0) → (1,1); the center matched by the engine alone.
    const s = linkKeyframeElements(two(), kf(0, 0), kf(1, 1));
    const offered = {
      t: 0.5050505050505051,
      elements: [
        { kind: "singular" as const, type: "source", at: [0.1, -0.3] },
        { kind: "singular" as const, type: "ccw_center", at: [-0.1, 0.3] },
      ],
    };
    const m = S.insertMiddleKeyframe(s, 0, offered, [0, 1], [1, 0]);
    expect(m.keyframes?.map((k) => k.t)).toEqual([0, 0.5050505050505051, 1]);
    expect(m.keyframes?.[1]).toEqual(offered);
    expect(m.solver?.keyframe_topology).toBe("matched");
    // The link goes on through the new key frame's source; the center had none.
    expect(keyframeLinks(m)).toEqual([
      { from: [0, 0], to: [1, 0] },
      { from: [1, 0], to: [2, 1] },
    ]);
    // Without links none is made; the scene given is left as it was.
    const plain = S.insertMiddleKeyframe(setKeyframeTopology(two(), true), 0, offered, [0, 1], [1, 0]);
    expect(keyframeLinks(plain)).toEqual([]);
    expect(s.keyframes?.length).toBe(2);
    // No room (a key frame already at that frame, or none after the one named): refused.
    expect(() => S.insertMiddleKeyframe(m, 0, offered, [0, 1], [1, 0])).toThrow(/the key frames changed/);
    expect(() => S.insertMiddleKeyframe(s, 1, offered, [0, 1], [1, 0])).toThrow(/the key frames changed/);
  });
});
