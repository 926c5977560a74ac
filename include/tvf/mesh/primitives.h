#pragma once
// Meshes made in code: used by examples (no mesh files in git) and by the tests' mesh
// catalogue.
#include "tvf/mesh/mesh.h"

namespace tvf {

// Icosahedron subdivided `subdivisions` times, projected to a sphere of `radius`
// (10·4^s + 2 vertices; s = 5 gives 10,242 and s = 6 gives 40,962).
Mesh make_icosphere(int subdivisions, double radius = 1.0);
// Geodesic sphere of frequency k: every icosahedron edge cut into k parts, each face into
// k² triangles, projected to the sphere (10·k² + 2 vertices; k = 45 gives 20,252, the
// size of the paper's largest surface).
Mesh make_geodesic_sphere(int frequency, double radius = 1.0);
// Torus around the z axis: major radius R, minor radius r, nu × nv vertices.
Mesh make_torus(int nu, int nv, double R = 1.0, double r = 0.35);

}  // namespace tvf
