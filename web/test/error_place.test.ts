import { describe, expect, it } from "vitest";
import { locateJsonPath } from "../src/error_place";

describe("locateJsonPath", () => {
  const text = JSON.stringify(
    { tvf: 1, time: { frames: -3, range: [0, 1] }, elements: [{ kind: "singular", type: "sourse", path: [[0, 0, 0]] }] },
    null,
    2,
  );
  const at = (path: string) => {
    const r = locateJsonPath(text, path);
    return r && text.slice(r.start, r.end);
  };
  it("finds the value a server error names", () => {
    expect(at("time.frames")).toBe("-3");
    expect(at("elements[0].type")).toBe('"sourse"');
    expect(at("elements[0].path[0]")?.replace(/\s/g, "")).toBe("[0,0,0]");
    expect(at("time.range[1]")).toBe("1");
    expect(at("time")?.startsWith("{")).toBe(true);
  });
  it("says nothing for a place the text does not have", () => {
    expect(at("time.frame")).toBeUndefined();
    expect(at("elements[1]")).toBeUndefined();
    expect(at("tvf.x")).toBeUndefined();
    expect(at("a..b")).toBeUndefined();
  });
  it("skips strings with brackets and escaped quotes", () => {
    const t = '{"a\\"b": "x]}", "a": [1, "]", {"c": true}]}';
    const r = locateJsonPath(t, "a[2].c");
    expect(r && t.slice(r.start, r.end)).toBe("true");
  });
});
