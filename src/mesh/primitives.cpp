#include "tvf/mesh/primitives.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace tvf {

namespace {

void icosahedron(std::vector<Vec3>& v, std::vector<Face>& f) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, p, 0}, {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
       {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9},  {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6},  {3, 6, 8},
       {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& x : v) x.normalize();
}

}  // namespace

Mesh make_geodesic_sphere(int frequency, double radius) {
  if (frequency < 1 || frequency > 1000)
    throw_input_error("geodesic sphere", "frequency", fmt::format("{} is outside [1, 1000]", frequency));
  std::vector<Vec3> ico;
  std::vector<Face> ico_faces;
  icosahedron(ico, ico_faces);
  const int k = frequency;
  // A point is named by its integer barycentric weights on icosahedron vertices (sorted
  // by vertex), so the faces sharing an edge or a corner make the same point once, with
  // the same rounding.
  using Key = std::array<int, 6>;
  std::map<Key, int> ids;
  std::vector<Vec3> v;
  auto point = [&](const Face& t, int i, int j) {
    std::array<std::pair<int, int>, 3> w = {{{t[0], k - i - j}, {t[1], i}, {t[2], j}}};
    std::sort(w.begin(), w.end());
    Key key{};
    int n = 0;
    for (const auto& [id, weight] : w)
      if (weight > 0) key[static_cast<size_t>(2 * n)] = id, key[static_cast<size_t>(2 * n + 1)] = weight, ++n;
    for (int m = n; m < 3; ++m) key[static_cast<size_t>(2 * m)] = -1;
    const auto [it, fresh] = ids.emplace(key, static_cast<int>(v.size()));
    if (fresh) {
      Vec3 x = Vec3::Zero();
      for (int m = 0; m < n; ++m)
        x += static_cast<double>(key[static_cast<size_t>(2 * m + 1)]) * ico[static_cast<size_t>(key[static_cast<size_t>(2 * m)])];
      v.push_back(radius * x.normalized());
    }
    return it->second;
  };
  std::vector<Face> f;
  f.reserve(ico_faces.size() * static_cast<size_t>(k) * static_cast<size_t>(k));
  for (const Face& t : ico_faces)
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        f.push_back({point(t, i, j), point(t, i + 1, j), point(t, i, j + 1)});
        if (i + j + 2 <= k) f.push_back({point(t, i + 1, j), point(t, i + 1, j + 1), point(t, i, j + 1)});
      }
  return Mesh(std::move(v), std::move(f), fmt::format("geodesic sphere({})", frequency));
}

Mesh make_icosphere(int subdivisions, double radius) {
  if (subdivisions < 0 || subdivisions > 9)
    throw_input_error("icosphere", "subdivisions", fmt::format("{} is outside [0, 9]", subdivisions));
  std::vector<Vec3> v;
  std::vector<Face> f;
  icosahedron(v, f);
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
