#include "fem/element_product.hpp"

namespace msfab {
namespace {

// Eight doubles, loaded from and stored to 8-byte aligned memory: GCC
// lowers each operation to what the enclosing function's target offers
// (one AVX-512 instruction, two AVX2 or four SSE ones).
typedef double Lanes8 __attribute__((vector_size(64), aligned(8)));

// Inlined into each target below and compiled for it. Per column c:
// s = w x_c, then y += s K_c as a product and a sum (this file is
// compiled with -ffp-contract=off, so no variant fuses them).
__attribute__((always_inline)) inline void product_body(const double* K, double w, const double* x, double* y) {
  Lanes8 y0 = *reinterpret_cast<const Lanes8*>(y), y1 = *reinterpret_cast<const Lanes8*>(y + 8),
         y2 = *reinterpret_cast<const Lanes8*>(y + 16);
  for (int c = 0; c < 24; ++c) {
    const double s = w * x[c];
    const double* column = K + 24 * c;
    y0 = y0 + s * *reinterpret_cast<const Lanes8*>(column);
    y1 = y1 + s * *reinterpret_cast<const Lanes8*>(column + 8);
    y2 = y2 + s * *reinterpret_cast<const Lanes8*>(column + 16);
  }
  *reinterpret_cast<Lanes8*>(y) = y0;
  *reinterpret_cast<Lanes8*>(y + 8) = y1;
  *reinterpret_cast<Lanes8*>(y + 16) = y2;
}

void product_sse(const double* K, double w, const double* x, double* y) { product_body(K, w, x, y); }

__attribute__((target("avx2"))) void product_avx2(const double* K, double w, const double* x, double* y) {
  product_body(K, w, x, y);
}

__attribute__((target("avx512f"))) void product_avx512(const double* K, double w, const double* x, double* y) {
  product_body(K, w, x, y);
}

struct Choice {
  ElementProductKernel kernel;
  const char* name;
};

Choice choose() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) return {product_avx512, "avx512"};
  if (__builtin_cpu_supports("avx2")) return {product_avx2, "avx2"};
  return {product_sse, "sse"};
}

const Choice& chosen() {
  static const Choice choice = choose();
  return choice;
}

}  // namespace

ElementProductKernel element_product_kernel() { return chosen().kernel; }

const char* element_product_kernel_name() { return chosen().name; }

ElementProductKernel element_product_kernel(const std::string& name) {
  __builtin_cpu_init();
  if (name == "sse") return product_sse;
  if (name == "avx2") return __builtin_cpu_supports("avx2") ? product_avx2 : nullptr;
  if (name == "avx512") return __builtin_cpu_supports("avx512f") ? product_avx512 : nullptr;
  return nullptr;
}

}  // namespace msfab
