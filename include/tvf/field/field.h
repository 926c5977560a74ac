#pragma once
// A time-varying tangent vector field (DESIGN §3): N frames × |V| complex numbers,
// frame-major (one frame contiguous). Value (j, v) is the vector at vertex v at time
// t_j in v's tangent basis (TangentBundle::vertex_e1/e2).
#include "tvf/core/types.h"
#include "tvf/field/time_sampling.h"

#include <span>
#include <vector>

namespace tvf {

class Field {
public:
  Field() = default;
  Field(TimeSampling time, int num_vertices)
      : time_(time), nv_(num_vertices),
        data_(static_cast<size_t>(time.frames) * static_cast<size_t>(num_vertices)) {}

  const TimeSampling& time() const { return time_; }
  int frames() const { return time_.frames; }
  int num_vertices() const { return nv_; }

  std::span<cplx> frame(int j) {
    return {data_.data() + static_cast<size_t>(j) * static_cast<size_t>(nv_),
            static_cast<size_t>(nv_)};
  }
  std::span<const cplx> frame(int j) const {
    return {data_.data() + static_cast<size_t>(j) * static_cast<size_t>(nv_),
            static_cast<size_t>(nv_)};
  }
  cplx& at(int j, int v) { return data_[static_cast<size_t>(j) * static_cast<size_t>(nv_) + static_cast<size_t>(v)]; }
  cplx at(int j, int v) const { return data_[static_cast<size_t>(j) * static_cast<size_t>(nv_) + static_cast<size_t>(v)]; }
  std::vector<cplx>& data() { return data_; }
  const std::vector<cplx>& data() const { return data_; }

private:
  TimeSampling time_;
  int nv_ = 0;
  std::vector<cplx> data_;
};

}  // namespace tvf
