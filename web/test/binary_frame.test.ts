// The binary frame of GET /api/frame/J?format=f32 (docs/serve_api.md, "Binary frames"),
// read as the server writes it: a little-endian length, the JSON head padded to a multiple
// of 4, then little-endian float32 vectors.
import { describe, expect, it } from "vitest";
import { parseBinaryFrame } from "../src/api";

function encode(head: object, values: number[]): ArrayBuffer {
  let text = JSON.stringify({ ...head, count: values.length });
  text += " ".repeat((4 - ((4 + text.length) % 4)) % 4);
  const bytes = new TextEncoder().encode(text);
  const out = new ArrayBuffer(4 + bytes.length + 4 * values.length);
  const view = new DataView(out);
  view.setUint32(0, bytes.length, true);
  new Uint8Array(out, 4, bytes.length).set(bytes);
  values.forEach((v, k) => view.setFloat32(4 + bytes.length + 4 * k, v, true));
  return out;
}

describe("parseBinaryFrame", () => {
  it("reads the head and the float32 vectors", () => {
    const head = { revision: 7, frame: 3, frames: 100, t: 0.0303, singularities: [{ position: [0.1, -0.2], type: "source", index: 1, path: -1 }] };
    const values = [0.5, -1.25, 0, 3.0e-8, 1e6, -0];
    const f = parseBinaryFrame(encode(head, values));
    expect(f.revision).toBe(7);
    expect(f.frame).toBe(3);
    expect(f.frames).toBe(100);
    expect(f.t).toBe(0.0303);
    expect(f.singularities).toEqual(head.singularities);
    expect("count" in f).toBe(false);
    expect(Array.from(f.vectors)).toEqual(values.map((v) => Math.fround(v)));
  });
  it("refuses a frame shorter than its head says", () => {
    const bytes = encode({ revision: 1, frame: 0, frames: 2, t: 0, singularities: [] }, [1, 2, 3]);
    expect(() => parseBinaryFrame(bytes.slice(0, bytes.byteLength - 4))).toThrow(/wrong length/);
  });
});
