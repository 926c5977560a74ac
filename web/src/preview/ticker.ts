// The clock of the moving previews: calls `tick` about `fps` times a second while the
// page is shown (requestAnimationFrame stops in hidden tabs), whether the page is idle,
// scrubbed or playing. A tick never takes more than a third of the page's time: when
// ticks get slow (a big mesh, a loaded machine) they come less often, so that clicks and
// the server's answers are handled without delay. Paused, it only steps when asked
// (step(n)): the end-to-end tests pause it to compare two pictures a known number of
// steps apart.
export class Ticker {
  paused = false;
  private last = 0;
  private handle = 0;
  private cost = 0; // ms a tick takes (a running mean)

  constructor(
    private readonly tick: (steps: number) => void,
    private readonly fps = 30,
  ) {}

  start() {
    const loop = (now: number) => {
      this.handle = requestAnimationFrame(loop);
      if (this.paused || now - this.last < Math.max(1000 / this.fps, 3 * this.cost) - 2) return;
      this.last = now;
      const start = performance.now();
      this.tick(1);
      this.cost = 0.8 * this.cost + 0.2 * (performance.now() - start);
    };
    cancelAnimationFrame(this.handle);
    this.handle = requestAnimationFrame(loop);
  }

  step(n: number) {
    this.tick(n);
  }
}
