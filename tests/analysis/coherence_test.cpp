#include "tvf/analysis/coherence.h"

#include <gtest/gtest.h>

#include <random>
#include <sstream>

namespace tvf {
namespace {

TEST(Coherence, ConstantChangeGivesVertexCountTimesItsLength) {
  // Frame j holds j·c at every vertex: every step changes each vertex by c, |c| = 5.
  const cplx c(3.0, -4.0);
  Field field(TimeSampling{0.0, 1.0, 12}, 37);
  for (int j = 0; j < field.frames(); ++j)
    for (int v = 0; v < field.num_vertices(); ++v) field.at(j, v) = static_cast<double>(j) * c;
  const std::vector<double> y = coherence(field);
  ASSERT_EQ(y.size(), 11u);
  for (double yi : y) EXPECT_EQ(yi, 37 * 5.0);
}

TEST(Coherence, SumsThePerVertexChange) {
  // z_jk = a_k + j²·c_k: step i changes vertex k by (2i + 1)·c_k.
  const int nv = 50;
  std::mt19937 rng(2);
  std::normal_distribution<double> g;
  std::vector<cplx> a(nv), c(nv);
  double sum_c = 0;
  for (int k = 0; k < nv; ++k) {
    a[static_cast<size_t>(k)] = {g(rng), g(rng)};
    c[static_cast<size_t>(k)] = {g(rng), g(rng)};
    sum_c += std::abs(c[static_cast<size_t>(k)]);
  }
  Field field(TimeSampling{-1.0, 1.0, 6}, nv);
  for (int j = 0; j < 6; ++j)
    for (int k = 0; k < nv; ++k)
      field.at(j, k) = a[static_cast<size_t>(k)] + static_cast<double>(j * j) * c[static_cast<size_t>(k)];
  const std::vector<double> y = coherence(field);
  ASSERT_EQ(y.size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_NEAR(y[i], static_cast<double>(2 * i + 1) * sum_c, 1e-12 * sum_c * 10) << i;
  // A static field is perfectly coherent.
  Field still(TimeSampling{0, 1, 4}, nv);
  for (int j = 0; j < 4; ++j)
    for (int k = 0; k < nv; ++k) still.at(j, k) = a[static_cast<size_t>(k)];
  EXPECT_EQ(coherence(still), std::vector<double>(3, 0.0));
}

TEST(Coherence, SingleFrameHasNoSteps) {
  Field field(TimeSampling{0, 1, 1}, 3);
  EXPECT_TRUE(coherence(field).empty());
  EXPECT_EQ(coherence_csv(field, {}), "frame,t,coherence\n");
}

TEST(Coherence, CsvHasFullPrecision) {
  Field field(TimeSampling{0.0, 1.0, 4}, 1);  // t = 0, 1/3, 2/3, 1
  const std::vector<double> y{0.1, 1.0 / 3.0, 2.5e-17};
  const std::string csv = coherence_csv(field, y);
  EXPECT_EQ(csv,
            "frame,t,coherence\n"
            "0,0,0.10000000000000001\n"
            "1,0.33333333333333331,0.33333333333333331\n"
            "2,0.66666666666666663,2.4999999999999999e-17\n");
  // Every number reads back bit-identical.
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  for (size_t i = 0; i < y.size(); ++i) {
    ASSERT_TRUE(std::getline(in, line));
    const size_t a = line.find(','), b = line.rfind(',');
    EXPECT_EQ(std::stoul(line.substr(0, a)), i);
    EXPECT_EQ(std::stod(line.substr(a + 1, b - a - 1)), field.time().time(static_cast<int>(i)));
    EXPECT_EQ(std::stod(line.substr(b + 1)), y[i]);
  }
}

}  // namespace
}  // namespace tvf
