import { describe, expect, it } from "vitest";
import type { SceneState } from "../src/api";
import { ChangeQueue } from "../src/changes";
import * as S from "../src/scene";

// A server as tvf serve keeps the scene: a revision, If-Match checked (412), answers
// after a delay.
class FakeServer {
  revision = 1;
  scene: S.Scene = S.emptyScene();
  puts = 0;
  state(): SceneState {
    return { revision: this.revision, scene: JSON.parse(JSON.stringify(this.scene)), path: "scene.json", can_undo: false, can_redo: false };
  }
  async put(scene: S.Scene, revision: number, delay = 5): Promise<SceneState> {
    await new Promise((r) => setTimeout(r, delay));
    ++this.puts;
    if (revision !== this.revision) throw Object.assign(new Error("stale"), { status: 412 });
    this.scene = scene;
    ++this.revision;
    return this.state();
  }
}

function tab(server: FakeServer) {
  let shown: SceneState | undefined = server.state();
  const queue = new ChangeQueue({
    current: () => shown,
    put: (s, r) => server.put(s, r),
    reload: async () => server.state(),
    show: (s) => (shown = s),
  });
  return { queue, shown: () => shown! };
}

const sink = (x: number) => (s: S.Scene) => S.addSingular(s, "sink", [x, 0], undefined, 0);

describe("the page's changes", () => {
  it("four clicks 5 ms apart in one tab all reach the scene, in order", async () => {
    const server = new FakeServer();
    const a = tab(server);
    const done: Promise<unknown>[] = [];
    for (let k = 0; k < 4; ++k) {
      done.push(a.queue.change(sink(k / 10)));
      await new Promise((r) => setTimeout(r, 5));
    }
    await Promise.all(done);
    expect(server.scene.elements!.map((e) => (e as S.SingularElement).path[0][0])).toEqual([0, 0.1, 0.2, 0.3]);
    expect(server.puts).toBe(4); // each made on the revision before it: no refusals
    expect(a.shown().revision).toBe(5);
  });

  it("a stale tab's change is refused, then applied on top of the other tab's", async () => {
    const server = new FakeServer();
    const a = tab(server);
    const b = tab(server); // opened before A's change
    await a.queue.change(sink(0.5));
    const r = await b.queue.change((s) => S.addSingular(s, "saddle", [-0.5, 0], undefined, 0));
    expect(r.applied && r.rebased).toBe(true);
    expect(server.scene.elements!.map((e) => (e as S.SingularElement).type)).toEqual(["sink", "saddle"]);
    expect(b.shown().revision).toBe(3);
  });

  it("a change that cannot be rebased is not applied, and the tab shows the other's scene", async () => {
    const server = new FakeServer();
    const a = tab(server);
    const b = tab(server);
    await a.queue.change(sink(0.5));
    const typed = { ...S.emptyScene(), falloff: 3 };
    const r = await b.queue.change(() => typed, false);
    expect(r.applied).toBe(false);
    expect(server.scene.elements).toHaveLength(1);
    expect(server.scene.falloff).toBe(8);
    expect(b.shown().scene.elements).toHaveLength(1);
  });

  it("errors other than a stale revision reach the caller, and the queue goes on", async () => {
    const server = new FakeServer();
    const a = tab(server);
    await expect(a.queue.change(() => { throw new Error("no"); })).rejects.toThrow("no");
    await a.queue.change(sink(0));
    expect(server.scene.elements).toHaveLength(1);
    expect(a.queue.busy).toBe(false);
  });
});
