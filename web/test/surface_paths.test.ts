import * as THREE from "three";
import { describe, expect, it } from "vitest";
import type { Analysis } from "../src/api";
import { pathObjects, timeColor } from "../src/surface/paths";

const analysis: Analysis = {
  revision: 1,
  frames: 3,
  times: [0, 0.5, 1],
  paths: [
    // born inside the range, lives to its end
    { id: 0, type: "source", birth: 0.25, death: 1, points: [[1, 0, 0, 0.25], [0, 1, 0, 0.5], [0, 0, 1, 1]] },
    // lives from the start, dies inside
    { id: 1, type: "saddle", birth: 0, death: 0.75, points: [[-1, 0, 0, 0], [0, -1, 0, 0.75]] },
  ],
  bifurcations: [{ t: 0.25, position: [1, 0, 0], kind: "creation", paths: [0, 2] }],
  coherence: [0, 0, 0],
};

describe("the paths through time on a surface", () => {
  it("colours time from dark blue to yellow", () => {
    expect(timeColor(0)).toEqual([0.27, 0.0, 0.33]);
    expect(timeColor(1)).toEqual([0.99, 0.91, 0.14]);
    expect(timeColor(-3)).toEqual(timeColor(0));
    const mid = timeColor(0.5);
    expect(mid[0]).toBeCloseTo(0.13, 12);
    expect(mid[1]).toBeCloseTo(0.57, 12);
  });

  it("draws each path as a tube coloured by its times, births, deaths and bifurcations", () => {
    const objects = pathObjects(analysis, [0, 1], 1, 0);
    const tubes = objects.filter((o) => (o as THREE.Mesh).geometry instanceof THREE.TubeGeometry) as THREE.Mesh[];
    expect(tubes).toHaveLength(2);
    const colours = tubes[0].geometry.getAttribute("color");
    const n = colours.count;
    // The first ring has the colour of t = 0.25, the last of t = 1.
    const first = [colours.getX(0), colours.getY(0), colours.getZ(0)];
    const last = [colours.getX(n - 1), colours.getY(n - 1), colours.getZ(n - 1)];
    timeColor(0.25).forEach((c, k) => expect(first[k]).toBeCloseTo(c, 6));
    timeColor(1).forEach((c, k) => expect(last[k]).toBeCloseTo(c, 6));
    const balls = objects.filter((o) => (o as THREE.Mesh).geometry instanceof THREE.SphereGeometry) as THREE.Mesh[];
    // Path 0 is born inside the range (white, at its first point); path 1 dies inside
    // (black, at its last); neither ends nor starts at the range's edges otherwise.
    expect(balls).toHaveLength(2);
    const white = balls.find((b) => (b.material as THREE.MeshBasicMaterial).color.getHex() === 0xffffff)!;
    const black = balls.find((b) => (b.material as THREE.MeshBasicMaterial).color.getHex() === 0x000000)!;
    expect(white.position.toArray()).toEqual([1, 0, 0]);
    expect(black.position.toArray()).toEqual([0, -1, 0]);
    const diamonds = objects.filter((o) => (o as THREE.Mesh).geometry instanceof THREE.OctahedronGeometry) as THREE.Mesh[];
    expect(diamonds).toHaveLength(1);
    expect(diamonds[0].position.toArray()).toEqual([1, 0, 0]);
    // The picked bifurcation is drawn larger.
    const size = (o: THREE.Mesh) => (o.geometry as THREE.OctahedronGeometry).parameters.radius;
    const unpicked = pathObjects(analysis, [0, 1], 1, -1).find((o) => (o as THREE.Mesh).geometry instanceof THREE.OctahedronGeometry) as THREE.Mesh;
    expect(size(diamonds[0])).toBeGreaterThan(size(unpicked));
  });
});
