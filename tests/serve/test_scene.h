#pragma once
// A small design for the server tests: a flow to the right with a saddle and a source
// downstream of it (a pair that can be cancelled) and a centre (tests/cli/edit_test.cpp's).
namespace tvf::test {
inline constexpr const char* kServeScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 21, "range": [0, 1]},
  "generator": "constrained", "solver": {"region_radius": 0.15},
  "falloff": 20,
  "elements": [
    {"kind": "regular", "pathline": [[-0.9, -0.3, 0], [-0.8, -0.3, 1]]},
    {"kind": "singular", "jacobian": [[-1, 0], [0, 1]], "path": [[-0.3, -0.3, 0], [-0.25, -0.3, 1]]},
    {"kind": "singular", "type": "source", "path": [[0.2, -0.3, 0]]},
    {"kind": "singular", "type": "ccw_center", "path": [[0.1, 0.6, 0]]}]})";
}  // namespace tvf::test
