// Axis ticks and their labels, formatted by magnitude: a coherence of 2·10⁻⁴ is labelled
// "2e-4", not "0", and every label of an axis is distinct.

// About `count` round values (1, 2 or 5 × 10^k apart) covering [lo, hi].
export function niceTicks(lo: number, hi: number, count = 5): number[] {
  if (!(hi > lo) || !Number.isFinite(lo) || !Number.isFinite(hi)) return Number.isFinite(lo) ? [lo] : [];
  const raw = (hi - lo) / Math.max(1, count - 1);
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw * 0.999) ?? 10 * p;
  const out: number[] = [];
  for (let k = Math.ceil(lo / step - 1e-9); k * step <= hi + step * 1e-9; ++k) out.push(Math.abs(k * step) < step * 1e-9 ? 0 : Number((k * step).toPrecision(12)));
  return out;
}

// Labels for the values of one axis: fixed decimals enough to tell neighbours apart, or
// exponents for values below 10⁻³ or from 10⁶ on.
export function formatTicks(values: number[]): string[] {
  const finite = values.filter(Number.isFinite);
  const maxAbs = Math.max(0, ...finite.map(Math.abs));
  if (maxAbs === 0) return values.map((v) => (v === 0 ? "0" : String(v)));
  const sorted = [...new Set(finite)].sort((a, b) => a - b);
  let step = Infinity;
  for (let i = 1; i < sorted.length; ++i) step = Math.min(step, sorted[i] - sorted[i - 1]);
  if (!Number.isFinite(step) || step <= 0) step = maxAbs;
  if (maxAbs < 1e-3 || maxAbs >= 1e6) {
    const digits = Math.min(6, Math.max(0, Math.ceil(Math.log10(maxAbs / step) - 1e-9)));
    return values.map((v) => (v === 0 ? "0" : v.toExponential(digits).replace(/\.?0+e/, "e").replace("e+", "e")));
  }
  const decimals = Math.min(10, Math.max(0, Math.ceil(-Math.log10(step) - 1e-9)));
  return values.map((v) => v.toFixed(decimals));
}
