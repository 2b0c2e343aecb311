// column_products (quadric/sample_columns.hpp): Y = Σ_k c_k c_kᵀ against a double-precision sum
// of the same float columns, for every column count the blocks can meet (1..10) and several
// sample counts: every entry of the top-left cols x cols written, both triangles equal, and
// nothing outside it touched.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "jpcr/quadric/sample_columns.hpp"

namespace jpcr {
namespace {

template <typename Lane>
void check_products(int cols, int n, std::mt19937& rng) {
  constexpr int kLanes = 32 / sizeof(Lane);
  const int stride = n + kLanes;  // room past n, as the callers' capacity
  std::normal_distribution<double> value(0.0, 1.0);
  std::vector<Lane> columns(static_cast<std::size_t>(cols) * stride, Lane(0));
  for (int c = 0; c < cols; ++c)
    for (int k = 0; k < n; ++k)  // the padding of each column stays zero
      columns[static_cast<std::size_t>(c) * stride + k] = static_cast<Lane>(value(rng));
  constexpr double kUntouched = -12345.0;
  std::vector<double> Y(100, kUntouched);
  column_products<Lane>(columns.data(), n, stride, cols, Y.data());
  for (int a = 0; a < 10; ++a) {
    for (int b = 0; b < 10; ++b) {
      const double got = Y[a * 10 + b];
      if (a >= cols || b >= cols) {
        EXPECT_EQ(got, kUntouched) << "cols " << cols << ", Y(" << a << ", " << b << ")";
        continue;
      }
      double want = 0.0, scale = 0.0;
      for (int k = 0; k < n; ++k) {
        const double p = static_cast<double>(columns[static_cast<std::size_t>(a) * stride + k]) *
                         columns[static_cast<std::size_t>(b) * stride + k];
        want += p;
        scale += std::abs(p);
      }
      // Lanes accumulate in Lane: each of the n / kLanes steps rounds relative to the sum.
      const double tolerance =
          4.0 * std::numeric_limits<Lane>::epsilon() * (n / kLanes + 1) * scale + 1e-300;
      EXPECT_NEAR(got, want, tolerance)
          << "cols " << cols << ", n " << n << ", Y(" << a << ", " << b << ")";
      EXPECT_EQ(got, Y[b * 10 + a]) << "cols " << cols << ": both triangles";
    }
  }
}

TEST(SampleColumns, ProductsMatchADoubleSumForEveryColumnCount) {
  std::mt19937 rng(7);
  for (int cols = 1; cols <= 10; ++cols)
    for (const int registers : {0, 1, 2, 5, 17}) {
      check_products<float>(cols, registers * 8, rng);
      check_products<double>(cols, registers * 4, rng);
    }
}

}  // namespace
}  // namespace jpcr
