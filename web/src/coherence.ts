// The coherence plot (paper Fig. 18): y_i = Σ_k ‖V_k(t_{i+1}) − V_k(t_i)‖ against t_i,
// with a marker at the current time. uPlot draws it.
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { formatTicks } from "./ticks";

export class CoherencePlot {
  private plot: uPlot | undefined;
  private time = 0;
  constructor(private readonly host: HTMLElement) {}

  set(times: number[], coherence: number[]) {
    const xs = times.slice(0, coherence.length);
    const data: uPlot.AlignedData = [xs, coherence];
    if (this.plot) {
      this.plot.setData(data);
      return;
    }
    const width = this.host.clientWidth || 360;
    this.plot = new uPlot(
      {
        width,
        height: 150,
        legend: { show: false },
        cursor: { show: false },
        scales: { x: { time: false } },
        // Labels by magnitude: small coherences are not all "0".
        axes: [
          { label: "t", values: (_u, splits) => formatTicks(splits) },
          { label: "coherence", size: 60, values: (_u, splits) => formatTicks(splits) },
        ],
        series: [{}, { stroke: "#334155", width: 1.5 }],
        hooks: {
          draw: [
            (u) => {
              const x = u.valToPos(this.time, "x", true);
              const ctx = u.ctx;
              ctx.save();
              ctx.strokeStyle = "#ef4444";
              ctx.lineWidth = 2;
              ctx.beginPath();
              ctx.moveTo(x, u.bbox.top);
              ctx.lineTo(x, u.bbox.top + u.bbox.height);
              ctx.stroke();
              ctx.restore();
            },
          ],
        },
      },
      data,
      this.host,
    );
  }

  setTime(t: number) {
    this.time = t;
    this.plot?.redraw(false, false);
  }
}
