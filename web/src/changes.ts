// The page's changes to the scene, one at a time, each made on the revision it names
// (docs/serve_api.md, "Revisions"). A change is a function of the scene, applied to the
// newest scene the page knows when its turn comes, so quick clicks build on each other
// instead of each replacing the scene the page showed when it was clicked. When the
// server refuses a change because another tab or client changed the scene since (412),
// the page reloads the scene and applies the change again on top of it (a rebase), or,
// for a change that cannot be rebased (a whole scene typed as JSON), keeps the reloaded
// scene and says that the change was not applied. Nothing is lost silently.
import type { SceneState } from "./api";
import type { Scene } from "./scene";

export interface ChangeIo {
  current(): SceneState | undefined; // the scene the page shows
  put(scene: Scene, revision: number): Promise<SceneState>;
  reload(): Promise<SceneState>;
  show(state: SceneState): void;
}

export type Outcome =
  | { applied: true; state: SceneState; rebased: boolean } // rebased: on another client's change
  | { applied: false; state: SceneState }; // a change that could not be rebased, not applied

function isStale(e: unknown): boolean {
  return (e as { status?: number }).status === 412;
}

export class ChangeQueue {
  private tail: Promise<unknown> = Promise.resolve();
  private waiting = 0;

  constructor(private readonly io: ChangeIo) {}

  // Changes queued or under way (the page does not follow other tabs meanwhile).
  get busy(): boolean {
    return this.waiting > 0;
  }

  // Runs `task` after everything queued before it.
  run<T>(task: () => Promise<T>): Promise<T> {
    ++this.waiting;
    const next = this.tail.then(task, task);
    this.tail = next.then(
      () => --this.waiting,
      () => --this.waiting,
    );
    return next;
  }

  // Queues a change. `mutate` may throw (a change that makes no sense): the error is the
  // promise's. At most `attempts` rebases.
  change(mutate: (scene: Scene) => Scene, rebase = true, attempts = 5): Promise<Outcome> {
    return this.run(async () => {
      let rebased = false;
      for (let attempt = 0; ; ++attempt) {
        let base = this.io.current();
        if (!base) {
          base = await this.io.reload();
          this.io.show(base);
        }
        const next = mutate(base.scene);
        try {
          const state = await this.io.put(next, base.revision);
          this.io.show(state);
          return { applied: true, state, rebased };
        } catch (e) {
          if (!isStale(e) || attempt >= attempts) throw e;
          const fresh = await this.io.reload();
          this.io.show(fresh);
          if (!rebase) return { applied: false, state: fresh };
          rebased = true;
        }
      }
    });
  }
}
