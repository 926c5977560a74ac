#pragma once
// Re-solving a region of one frame (DESIGN §7; Zhang et al. 2006, "Vector field design on
// surfaces", pair cancellation). A region is a set of faces; its interior vertices (every
// face around them in the region) are re-solved by the connection Laplacian (L z = 0) with
// every other vertex fixed at its current value, so faces outside the region keep their
// values exactly, and the index of the region's boundary (the sum of the face indices
// inside) is what the solve has to fill in. Domain boundary vertices of the region are free
// (the design's natural boundary condition), so a singularity may also leave through the
// domain boundary: fixing them kept pairs next to the boundary from cancelling at all.
//
// The solve is the Dirichlet problem of DirichletSolver restricted to the region: only the
// block L_II of the interior vertices is factored (L_II z_I = −L_IB z_B), a few hundred
// vertices rather than the whole mesh, once per region and shared by the tries on it.
//
// The region starts from seed faces and grows one vertex ring at a time until the result
// is accepted. Singular faces that are not to be edited ("others") are never taken into the
// region, and the region never closes around one (a hole holding a singularity, whose
// index the harmonic fill would have to carry around it): a ring that would swallow
// another singularity ends the growth, and the edit fails naming it.
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/solve/connection_laplacian.h"

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tvf {

struct RegionOptions {
  int max_growth = 48;  // rings added to the seed before giving up
};

struct RegionResult {
  bool success = false;
  std::vector<cplx> values;   // the edited frame (|V| values in vertex bases)
  std::vector<int> faces;     // the final region (ascending)
  std::vector<char> interior; // |V|: 1 at the re-solved vertices
  int growths = 0;            // rings added before success (or before giving up)
  int remaining = 0;          // unwanted singular faces left in the region by the last try
  int blocked_by = -1;        // the singular face that stopped the growth (-1: the ring limit)
};

class RegionSolver {
public:
  // `laplacian` must belong to `bundle`'s mesh and outlive the solver.
  RegionSolver(const TangentBundle& bundle, const ConnectionLaplacian& laplacian,
               RegionOptions options = {});

  // Cancels the singularities of faces face_a and face_b (opposite indices) of `values`:
  // the seed is a shortest chain of faces from one to the other that avoids every other
  // singular face, plus one ring; success when no singular face is left in the region.
  // `start_rings` extra rings are added to the seed before the first try (a hint, e.g. what
  // the previous frame needed; growths then counts them).
  RegionResult cancel(std::span<const cplx> values, int face_a, int face_b, int start_rings = 0);

  // As cancel(), with `region` (faces) as the seed: used to cancel a pair at many frames
  // over one common region, so that consecutive frames get consecutive fills.
  RegionResult cancel_in(std::span<const cplx> values, int face_a, int face_b, const std::vector<int>& region);

  // Re-solves the neighbourhood of `pinned` vertices, which take `pinned_values` (one per
  // pinned vertex) and are held fixed: the seed is the faces around them, a chain of faces
  // from them to each face of `ignore`, plus one ring; success when every singular face
  // left in the region has its three corners pinned (the pasted singularities themselves).
  // `ignore` lists singular faces of `values` that are being replaced: they are taken into
  // the region, so that the paste moves them rather than adding a copy.
  RegionResult paste(std::span<const cplx> values, const std::vector<int>& pinned,
                     std::span<const cplx> pinned_values, const std::vector<int>& ignore = {});

private:
  const TangentBundle& bundle_;
  const ConnectionLaplacian& laplacian_;
  RegionOptions options_;
  std::vector<std::vector<int>> vertex_faces_;
};

}  // namespace tvf
