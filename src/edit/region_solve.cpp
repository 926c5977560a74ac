#include "tvf/edit/region_solve.h"

#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include <algorithm>
#include <functional>
#include <limits>
#include <queue>

namespace tvf {
namespace {

Vec3 centroid(const Mesh& mesh, int f) {
  const Face& c = mesh.face(f);
  return (mesh.position(c[0]) + mesh.position(c[1]) + mesh.position(c[2])) / 3.0;
}

// Shortest chain of edge-adjacent faces from a to b (Dijkstra on centroid distances) that
// avoids blocked faces; empty when there is none.
std::vector<int> face_chain(const Mesh& mesh, int a, int b, const std::vector<char>& blocked) {
  const auto nf = static_cast<size_t>(mesh.num_faces());
  std::vector<double> dist(nf, std::numeric_limits<double>::infinity());
  std::vector<int> from(nf, -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[static_cast<size_t>(a)] = 0;
  queue.emplace(0.0, a);
  while (!queue.empty()) {
    const auto [d, f] = queue.top();
    queue.pop();
    if (d > dist[static_cast<size_t>(f)]) continue;
    if (f == b) break;
    for (int c = 0; c < 3; ++c) {
      const int tw = mesh.twin(3 * f + c);
      if (tw < 0) continue;
      const int g = Mesh::face_of(tw);
      if (blocked[static_cast<size_t>(g)] && g != b) continue;
      const double nd = d + (centroid(mesh, g) - centroid(mesh, f)).norm();
      if (nd < dist[static_cast<size_t>(g)]) {
        dist[static_cast<size_t>(g)] = nd;
        from[static_cast<size_t>(g)] = f;
        queue.emplace(nd, g);
      }
    }
  }
  std::vector<int> chain;
  if (!std::isfinite(dist[static_cast<size_t>(b)])) return chain;
  for (int f = b; f >= 0; f = from[static_cast<size_t>(f)]) chain.push_back(f);
  return chain;
}

// A blocked face that `region` encloses (-1 if none): one in a part of the complement cut
// off from the rest, that is, from the domain boundary, or on a closed mesh from the
// complement's largest part. Taking such a face's surroundings into the region would
// swallow its singularity.
int enclosed_blocked_face(const Mesh& mesh, const std::vector<char>& region, const std::vector<char>& blocked) {
  const auto nf = static_cast<size_t>(mesh.num_faces());
  std::vector<int> component(nf, -1);
  std::vector<int> sizes;
  std::vector<char> touches_boundary;
  std::vector<int> stack;
  for (size_t f0 = 0; f0 < nf; ++f0) {
    if (region[f0] || component[f0] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    sizes.push_back(0);
    touches_boundary.push_back(0);
    component[f0] = id;
    stack.assign(1, static_cast<int>(f0));
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      ++sizes.back();
      for (int c = 0; c < 3; ++c) {
        const int tw = mesh.twin(3 * f + c);
        if (tw < 0) {
          touches_boundary.back() = 1;
          continue;
        }
        const auto g = static_cast<size_t>(Mesh::face_of(tw));
        if (region[g] || component[g] >= 0) continue;
        component[g] = id;
        stack.push_back(static_cast<int>(g));
      }
    }
  }
  if (sizes.empty()) return -1;
  std::vector<char> outside(sizes.size(), 0);
  bool any = false;
  for (size_t k = 0; k < sizes.size(); ++k) any = any || touches_boundary[k];
  if (any) {
    outside = touches_boundary;
  } else {
    outside[static_cast<size_t>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin())] = 1;
  }
  for (size_t f = 0; f < nf; ++f)
    if (blocked[f] && !region[f] && !outside[static_cast<size_t>(component[f])]) return static_cast<int>(f);
  return -1;
}

}  // namespace

RegionSolver::RegionSolver(const TangentBundle& bundle, const ConnectionLaplacian& laplacian,
                           RegionOptions options)
    : bundle_(bundle), laplacian_(laplacian), options_(options) {
  const Mesh& mesh = bundle.mesh();
  vertex_faces_.resize(static_cast<size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v)
    for (int h : mesh.outgoing(v)) vertex_faces_[static_cast<size_t>(v)].push_back(Mesh::face_of(h));
}

namespace {

struct GrowInput {
  std::vector<char> region;   // seed faces (|F|)
  std::vector<char> blocked;  // faces never taken (|F|)
  std::vector<char> pinned;   // vertices held at pinned values (|V|)
  std::vector<cplx> start;    // the frame with pinned values written in
  Vec3 focus = Vec3::Zero();  // where the edit is (to name the nearest blocker)
};

}  // namespace

// L z = 0 at the interior vertices with every other vertex fixed: the block L_II factored
// (L_II z_I = −L_IB z_B). Hermitian weights: sparse LDLᵀ; mean-value weights: sparse LU.
class InteriorSolver {
public:
  InteriorSolver(const ConnectionLaplacian& laplacian, const std::vector<char>& interior)
      : laplacian_(laplacian) {
    const auto nv = interior.size();
    index_.assign(nv, -1);
    for (size_t v = 0; v < nv; ++v)
      if (interior[v]) index_[v] = n_++;
    if (n_ == 0 || n_ == static_cast<int>(nv)) return;  // nothing to solve, or nothing fixed
    std::vector<Eigen::Triplet<cplx>> triplets;
    const auto& l = laplacian.matrix;
    for (Eigen::Index c = 0; c < l.outerSize(); ++c) {
      const int ic = index_[static_cast<size_t>(c)];
      if (ic < 0) continue;
      for (Eigen::SparseMatrix<cplx>::InnerIterator it(l, c); it; ++it) {
        const int ir = index_[static_cast<size_t>(it.row())];
        if (ir >= 0) triplets.emplace_back(ir, ic, it.value());
      }
    }
    Eigen::SparseMatrix<cplx> a(n_, n_);
    a.setFromTriplets(triplets.begin(), triplets.end());
    if (laplacian.hermitian) {
      ldlt_.compute(a);
      ok_ = ldlt_.info() == Eigen::Success;
    } else {
      lu_.compute(a);
      ok_ = lu_.info() == Eigen::Success;
    }
  }
  bool ok() const { return ok_ || n_ == 0; }

  // out = values with the interior vertices re-solved.
  void solve(const std::vector<cplx>& values, std::vector<cplx>& out) const {
    out = values;
    if (n_ == 0) return;
    Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(n_);
    const auto& l = laplacian_.matrix;
    for (Eigen::Index c = 0; c < l.outerSize(); ++c) {
      if (index_[static_cast<size_t>(c)] >= 0) continue;
      const cplx zc = values[static_cast<size_t>(c)];
      if (zc == cplx(0, 0)) continue;
      for (Eigen::SparseMatrix<cplx>::InnerIterator it(l, c); it; ++it) {
        const int ir = index_[static_cast<size_t>(it.row())];
        if (ir >= 0) rhs[ir] -= it.value() * zc;
      }
    }
    const Eigen::VectorXcd z = laplacian_.hermitian ? Eigen::VectorXcd(ldlt_.solve(rhs)) : Eigen::VectorXcd(lu_.solve(rhs));
    for (size_t v = 0; v < index_.size(); ++v)
      if (index_[v] >= 0) out[v] = z[index_[v]];
  }

private:
  const ConnectionLaplacian& laplacian_;
  std::vector<int> index_;
  int n_ = 0;
  bool ok_ = false;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<cplx>> ldlt_;
  Eigen::SparseLU<Eigen::SparseMatrix<cplx>> lu_;
};

// The grow-and-solve loop shared by cancel() and paste().
static RegionResult grow_and_solve(const TangentBundle& bundle, const ConnectionLaplacian& laplacian,
                                   const std::vector<std::vector<int>>& vertex_faces, int max_growth,
                                   GrowInput in,
                                   const std::function<int(const std::vector<int>& index, int face)>& unwanted) {
  const Mesh& mesh = bundle.mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  RegionResult result;
  result.values.resize(nv);
  bool stuck = false;
  for (int growth = 0;; ++growth) {
    result.growths = growth;
    // Interior vertices: every face around them in the region. Domain boundary vertices in
    // the region are free too (the natural boundary condition of the design), so a
    // singularity may also leave through the domain boundary.
    result.interior.assign(nv, 0);
    for (size_t v = 0; v < nv; ++v) {
      if (in.pinned[v]) continue;
      bool inside = true;
      for (int f : vertex_faces[v]) inside = inside && in.region[static_cast<size_t>(f)];
      result.interior[v] = inside ? 1 : 0;
    }
    const InteriorSolver solver(laplacian, result.interior);
    if (!solver.ok()) break;  // e.g. a region that took the whole mesh: nothing holds it
    auto count_unwanted = [&](const std::vector<cplx>& values) {
      const std::vector<int> index = face_indices(bundle, values);
      int n = 0;
      for (size_t f = 0; f < nf; ++f)
        if (in.region[f] && index[f] != 0) n += unwanted(index, static_cast<int>(f));
      return n;
    };
    solver.solve(in.start, result.values);
    result.remaining = count_unwanted(result.values);
    if (result.remaining > 0) {
      // Second try on the same region: fill the directions and the magnitudes separately
      // (boundary values normalised, then the magnitudes |z| filled by the same solve), so
      // that boundary vectors of very different lengths (an element's basis field next to
      // its exponential falloff) cannot pull a zero into the region.
      std::vector<cplx> unit(nv), size(nv), directions(nv), sizes(nv);
      for (size_t v = 0; v < nv; ++v) {
        unit[v] = std::abs(in.start[v]) > 0 ? in.start[v] / std::abs(in.start[v]) : cplx(0, 0);
        size[v] = std::abs(in.start[v]);
      }
      solver.solve(unit, directions);
      solver.solve(size, sizes);
      {
        std::vector<cplx> split(in.start);
        for (size_t v = 0; v < nv; ++v)
          if (result.interior[v]) {
            const double a = std::abs(directions[v]);
            split[v] = a > 0 ? directions[v] / a * std::abs(sizes[v]) : cplx(0, 0);
          }
        const int remaining = count_unwanted(split);
        if (remaining < result.remaining) {
          result.values = std::move(split);
          result.remaining = remaining;
        }
      }
    }
    if (result.remaining == 0) {
      result.success = true;
      break;
    }
    if (growth >= max_growth) break;
    // Grow by one vertex ring, never into blocked faces.
    std::vector<char> next = in.region;
    bool grew = false;
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t f = 0; f < nf; ++f) {
      if (!in.region[f]) continue;
      for (int v : mesh.face(static_cast<int>(f)))
        for (int g : vertex_faces[static_cast<size_t>(v)]) {
          const auto gi = static_cast<size_t>(g);
          if (next[gi]) continue;
          if (in.blocked[gi]) {
            const double d = (centroid(mesh, g) - in.focus).norm();
            if (d < nearest) {
              nearest = d;
              result.blocked_by = g;
            }
            continue;
          }
          next[gi] = 1;
          grew = true;
        }
    }
    // A ring that would close around another singularity would swallow it: stop there.
    const int enclosed = grew ? enclosed_blocked_face(mesh, next, in.blocked) : -1;
    if (enclosed >= 0) result.blocked_by = enclosed;
    if (!grew || enclosed >= 0) {
      stuck = true;
      break;
    }
    in.region = std::move(next);
  }
  // Name a blocker only when it is what stopped the growth.
  if (result.success || !stuck) result.blocked_by = -1;
  for (size_t f = 0; f < nf; ++f)
    if (in.region[f]) result.faces.push_back(static_cast<int>(f));
  if (!result.success) result.values.assign(in.start.begin(), in.start.end());
  return result;
}

namespace {

// Adds one vertex ring to `region`, skipping blocked faces.
void dilate(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces, std::vector<char>& region,
            const std::vector<char>& blocked) {
  std::vector<char> next = region;
  for (size_t f = 0; f < region.size(); ++f) {
    if (!region[f]) continue;
    for (int v : mesh.face(static_cast<int>(f)))
      for (int g : vertex_faces[static_cast<size_t>(v)])
        if (!blocked[static_cast<size_t>(g)]) next[static_cast<size_t>(g)] = 1;
  }
  region = std::move(next);
}

}  // namespace

namespace {

// What a cancellation of the pair in faces a and b starts from: every other singular
// face blocked, nothing pinned, an empty region.
GrowInput cancellation_input(const TangentBundle& bundle, std::span<const cplx> values, int face_a, int face_b) {
  const Mesh& mesh = bundle.mesh();
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const std::vector<int> index = face_indices(bundle, values);
  GrowInput in;
  in.blocked.assign(nf, 0);
  for (size_t f = 0; f < nf; ++f)
    in.blocked[f] = index[f] != 0 && static_cast<int>(f) != face_a && static_cast<int>(f) != face_b;
  in.focus = (centroid(mesh, face_a) + centroid(mesh, face_b)) / 2;
  in.pinned.assign(static_cast<size_t>(mesh.num_vertices()), 0);
  in.start.assign(values.begin(), values.end());
  in.region.assign(nf, 0);
  return in;
}

}  // namespace

RegionResult RegionSolver::cancel(std::span<const cplx> values, int face_a, int face_b, int start_rings) {
  const Mesh& mesh = bundle_.mesh();
  const auto nf = static_cast<size_t>(mesh.num_faces());
  GrowInput in = cancellation_input(bundle_, values, face_a, face_b);
  const std::vector<int> chain = face_chain(mesh, face_a, face_b, in.blocked);
  if (chain.empty()) {
    RegionResult r;
    r.values = in.start;
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t f = 0; f < nf; ++f)
      if (in.blocked[f] && (centroid(mesh, static_cast<int>(f)) - in.focus).norm() < nearest) {
        nearest = (centroid(mesh, static_cast<int>(f)) - in.focus).norm();
        r.blocked_by = static_cast<int>(f);
      }
    r.remaining = 2;
    return r;
  }
  for (int f : chain) in.region[static_cast<size_t>(f)] = 1;
  // And the disc on the pair: a region hugging the chain is long and thin, and its harmonic
  // fill keeps the pair (the fill at the middle averages the boundary values nearest to it,
  // which point the way the field between the pair does).
  const Vec3 ca = centroid(mesh, face_a), cb = centroid(mesh, face_b);
  const double radius = (ca - cb).norm() / 2 + 2 * mesh.mean_edge_length();
  for (size_t f = 0; f < nf; ++f)
    if (!in.blocked[f] && (centroid(mesh, static_cast<int>(f)) - in.focus).norm() <= radius) in.region[f] = 1;
  const std::vector<char> chain_only = [&] {
    std::vector<char> r(nf, 0);
    for (int f : chain) r[static_cast<size_t>(f)] = 1;
    return r;
  }();
  const int extra = std::clamp(start_rings, 0, options_.max_growth);
  for (int k = 0; k <= extra; ++k) dilate(mesh, vertex_faces_, in.region, in.blocked);
  if (enclosed_blocked_face(mesh, in.region, in.blocked) >= 0) {
    // The disc (or the hinted rings) would swallow another singularity: the chain alone.
    in.region = chain_only;
    dilate(mesh, vertex_faces_, in.region, in.blocked);
    if (const int e = enclosed_blocked_face(mesh, in.region, in.blocked); e >= 0) {
      RegionResult r;
      r.values = in.start;
      r.blocked_by = e;
      r.remaining = 2;
      return r;
    }
  }
  RegionResult r = grow_and_solve(bundle_, laplacian_, vertex_faces_, options_.max_growth - extra, std::move(in),
                                  [](const std::vector<int>&, int) { return 1; });
  r.growths += extra;
  return r;
}

RegionResult RegionSolver::cancel_in(std::span<const cplx> values, int face_a, int face_b,
                                     const std::vector<int>& region) {
  const Mesh& mesh = bundle_.mesh();
  GrowInput in = cancellation_input(bundle_, values, face_a, face_b);
  for (int f : region)
    if (!in.blocked[static_cast<size_t>(f)]) in.region[static_cast<size_t>(f)] = 1;
  in.region[static_cast<size_t>(face_a)] = in.region[static_cast<size_t>(face_b)] = 1;
  if (const int e = enclosed_blocked_face(mesh, in.region, in.blocked); e >= 0) {
    RegionResult r;
    r.values = in.start;
    r.blocked_by = e;
    r.remaining = 2;
    return r;
  }
  return grow_and_solve(bundle_, laplacian_, vertex_faces_, options_.max_growth, std::move(in),
                        [](const std::vector<int>&, int) { return 1; });
}

RegionResult RegionSolver::paste(std::span<const cplx> values, const std::vector<int>& pinned,
                                 std::span<const cplx> pinned_values, const std::vector<int>& ignore) {
  TVF_CHECK(pinned.size() == pinned_values.size(), "{} pinned vertices, {} values", pinned.size(),
            pinned_values.size());
  TVF_CHECK(!pinned.empty(), "nothing to paste");
  const Mesh& mesh = bundle_.mesh();
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const std::vector<int> index = face_indices(bundle_, values);
  GrowInput in;
  in.blocked.assign(nf, 0);
  for (size_t f = 0; f < nf; ++f) in.blocked[f] = index[f] != 0;
  for (int f : ignore) in.blocked[static_cast<size_t>(f)] = 0;
  in.pinned.assign(nv, 0);
  in.start.assign(values.begin(), values.end());
  in.region.assign(nf, 0);
  Vec3 focus = Vec3::Zero();
  for (size_t k = 0; k < pinned.size(); ++k) {
    const auto v = static_cast<size_t>(pinned[k]);
    in.pinned[v] = 1;
    in.start[v] = pinned_values[k];
    focus += mesh.position(pinned[k]);
    for (int f : vertex_faces_[v]) in.region[static_cast<size_t>(f)] = 1;
  }
  in.focus = focus / static_cast<double>(pinned.size());
  // A pinned vertex next to a singularity that stays would move it: refuse by blocking.
  for (size_t f = 0; f < nf; ++f)
    if (in.region[f] && in.blocked[f]) {
      RegionResult r;
      r.values.assign(values.begin(), values.end());
      r.blocked_by = static_cast<int>(f);
      r.remaining = 1;
      return r;
    }
  // The singularities being replaced must be inside the region, or the paste would add a
  // copy and leave the original where it was (issue 16: at 65² the survivor of a three-path
  // removal was pasted a few cells away and the old one stayed, with new pairs around them):
  // a chain of faces from the pasted disc to each of them joins the seed.
  const int disc_face = vertex_faces_[static_cast<size_t>(pinned.front())].front();
  for (int f : ignore) {
    if (in.region[static_cast<size_t>(f)]) continue;
    const std::vector<int> chain = face_chain(mesh, disc_face, f, in.blocked);
    if (chain.empty()) {
      RegionResult r;
      r.values.assign(values.begin(), values.end());
      r.remaining = 1;
      return r;
    }
    for (int g : chain) in.region[static_cast<size_t>(g)] = 1;
  }
  dilate(mesh, vertex_faces_, in.region, in.blocked);
  if (const int e = enclosed_blocked_face(mesh, in.region, in.blocked); e >= 0) {
    RegionResult r;
    r.values.assign(values.begin(), values.end());
    r.blocked_by = e;
    r.remaining = 1;
    return r;
  }
  const std::vector<char> pinned_mask = in.pinned;
  // Only a face whose three corners are pinned holds a pasted singularity; a singular face
  // on the rim of the pasted disc (some corners solved) is one the fill made, and unwanted.
  return grow_and_solve(bundle_, laplacian_, vertex_faces_, options_.max_growth, std::move(in),
                        [&](const std::vector<int>&, int f) {
                          for (int v : mesh.face(f))
                            if (!pinned_mask[static_cast<size_t>(v)]) return 1;
                          return 0;
                        });
}

}  // namespace tvf
