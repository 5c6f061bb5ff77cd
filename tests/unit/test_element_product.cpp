// The element product's variants (fem/element_product.hpp): each one the
// CPU runs gives the same bits as the SSE one, and (in a build without
// fused multiply-add) as the column-by-column Eigen product it replaced,
// on random matrices, weights and vectors, accumulating into y.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include "core/types.hpp"
#include "fem/element_product.hpp"

namespace msfab {
namespace {

TEST(ElementProduct, EveryVariantGivesTheBitsOfTheEigenProduct) {
  std::mt19937 rng(17);
  std::normal_distribution<double> g;
  int variants = 0;
  for (const std::string name : {"sse", "avx2", "avx512"}) {
    const ElementProductKernel kernel = element_product_kernel(name);
    if (!kernel) continue;  // the CPU lacks it
    ++variants;
    for (int trial = 0; trial < 20; ++trial) {
      Mat24 K;
      Vec24 x, y0;
      for (int r = 0; r < 24; ++r) {
        x[r] = g(rng);
        y0[r] = g(rng);
        for (int c = 0; c < 24; ++c) K(r, c) = g(rng) * std::pow(10.0, int(rng() % 7) - 3);
      }
      const double w = std::abs(g(rng)) + 1e-3;
      Vec24 expected = y0;
      element_product_kernel("sse")(K.data(), w, x.data(), expected.data());
      Vec24 y = y0;
      kernel(K.data(), w, x.data(), y.data());
      EXPECT_EQ(0, std::memcmp(expected.data(), y.data(), sizeof(double) * 24)) << name << ", trial " << trial;
#ifndef __FMA__
      // Built without fused multiply-add (the default x86-64-v2), Eigen's
      // column-by-column product rounds the same way.
      Vec24 eigen = y0;
      for (int c = 0; c < 24; ++c) eigen += (w * x[c]) * K.col(c);
      EXPECT_EQ(0, std::memcmp(eigen.data(), y.data(), sizeof(double) * 24)) << name << ", trial " << trial;
#endif
    }
  }
  EXPECT_GE(variants, 1);
  EXPECT_EQ(nullptr, element_product_kernel("neon"));
  EXPECT_NE(nullptr, element_product_kernel());
  const std::string chosen = element_product_kernel_name();
  EXPECT_EQ(element_product_kernel(chosen), element_product_kernel());
}

}  // namespace
}  // namespace msfab
