import { describe, expect, it } from "vitest";
import { formatTicks, niceTicks } from "../src/ticks";

describe("axis labels", () => {
  it("label small values by their magnitude, never all as 0", () => {
    expect(formatTicks([0, 0.0002, 0.0004, 0.0006])).toEqual(["0", "2e-4", "4e-4", "6e-4"]);
    expect(formatTicks([0.00015, 0.0002, 0.00025])).toEqual(["1.5e-4", "2e-4", "2.5e-4"]);
    expect(formatTicks([0, 0.005, 0.01])).toEqual(["0.000", "0.005", "0.010"]);
    expect(formatTicks([0, 0.5, 1])).toEqual(["0.0", "0.5", "1.0"]);
    expect(formatTicks([0, 20, 40])).toEqual(["0", "20", "40"]);
    expect(formatTicks([0, 2e6, 4e6])).toEqual(["0", "2e6", "4e6"]);
    const labels = formatTicks([1e-5, 2e-5, 3e-5]);
    expect(new Set(labels).size).toBe(3);
  });

  it("put round ticks over a time range", () => {
    expect(niceTicks(0, 1, 5)).toEqual([0, 0.5, 1]);
    expect(niceTicks(0, 1, 6)).toEqual([0, 0.2, 0.4, 0.6, 0.8, 1]);
    expect(niceTicks(0, 3.7, 5)).toEqual([0, 1, 2, 3]);
    expect(niceTicks(2, 2, 5)).toEqual([2]);
  });
});
