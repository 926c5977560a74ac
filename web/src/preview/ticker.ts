// The clock of the moving previews: calls `tick` about `fps` times a second while the
// page is shown (requestAnimationFrame stops in hidden tabs), whether the page is idle,
// scrubbed or playing. Paused, it only steps when asked (step(n)): the end-to-end tests
// pause it to compare two pictures a known number of steps apart.
export class Ticker {
  paused = false;
  private last = 0;
  private handle = 0;

  constructor(
    private readonly tick: (steps: number) => void,
    private readonly fps = 30,
  ) {}

  start() {
    const loop = (now: number) => {
      this.handle = requestAnimationFrame(loop);
      if (this.paused || now - this.last < 1000 / this.fps - 2) return;
      this.last = now;
      this.tick(1);
    };
    cancelAnimationFrame(this.handle);
    this.handle = requestAnimationFrame(loop);
  }

  step(n: number) {
    this.tick(n);
  }
}
