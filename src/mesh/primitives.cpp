#include "tvf/mesh/primitives.h"

#include "tvf/core/error.h"

#include <cmath>
#include <map>

namespace tvf {

Mesh make_icosphere(int subdivisions, double radius) {
  if (subdivisions < 0 || subdivisions > 9)
    throw_input_error("icosphere", "subdivisions", fmt::format("{} is outside [0, 9]", subdivisions));
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, p, 0}, {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                         {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  std::vector<Face> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : v) x.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]).normalized());
      const int id = static_cast<int>(v.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<Face> g;
    g.reserve(f.size() * 4);
    for (const Face& t : f) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      g.push_back({t[0], a, c});
      g.push_back({t[1], b, a});
      g.push_back({t[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  for (auto& x : v) x *= radius;
  return Mesh(std::move(v), std::move(f), fmt::format("icosphere({})", subdivisions));
}

Mesh make_torus(int nu, int nv, double R, double r) {
  if (nu < 3 || nv < 3) throw_input_error("torus", "size", "needs at least 3 × 3 vertices");
  std::vector<Vec3> v;
  std::vector<Face> f;
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double w = 2 * kPi * j / nv;
      v.emplace_back((R + r * std::cos(w)) * std::cos(u), (R + r * std::cos(w)) * std::sin(u),
                     r * std::sin(w));
    }
  }
  auto id = [&](int i, int j) { return ((i % nu) * nv) + (j % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(std::move(v), std::move(f), fmt::format("torus({}x{})", nu, nv));
}

}  // namespace tvf
