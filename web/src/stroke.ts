// A drawn stroke turned into a few control points: resampled evenly by arc length, so a
// quick and a slow drawing of the same curve give the same points.
export function resample(points: number[][], count: number): number[][] {
  if (points.length < 2 || count < 2) return points.map((p) => [...p]);
  const cumulative = [0];
  for (let i = 1; i < points.length; ++i)
    cumulative.push(cumulative[i - 1] + Math.hypot(...points[i].map((v, k) => v - points[i - 1][k])));
  const total = cumulative[cumulative.length - 1];
  if (total === 0) return [points[0].slice(), points[0].slice()];
  const out: number[][] = [];
  let seg = 0;
  for (let k = 0; k < count; ++k) {
    const s = (total * k) / (count - 1);
    while (seg + 1 < points.length - 1 && cumulative[seg + 1] < s) ++seg;
    const a = points[seg];
    const b = points[seg + 1];
    const len = cumulative[seg + 1] - cumulative[seg];
    const w = len > 0 ? Math.min(1, Math.max(0, (s - cumulative[seg]) / len)) : 0;
    out.push(a.map((v, i) => Math.round((v + w * (b[i] - v)) * 1e4) / 1e4));
  }
  return out;
}
