// The line search's inversion bound per stencil: smallest_positive_det_root
// (kernels/fem/det_root.hpp) with the line search's cap 1/0.9, single-
// threaded, in 2D and 3D, on 10^6 fixed random stencils T = I + 0.2 R:
//   small  dT = 1e-3 R' (a late Newton step: the cheap clearance answers),
//   large  dT = R'      (an early step: most go to the polynomial's root),
//   mixed  small, with one in 50 a thousand times larger.
// Prints ns per stencil (best of 7 passes).
//   bench_det_root [--stencils N]
#include <Kokkos_Timer.hpp>
#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "kernels/fem/det_root.hpp"

using namespace bfemp;

namespace {

template <int dim>
double ns_per_stencil(int n, double step, int every, double every_factor) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Mat<dim>> T(n), dT(n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < dim; ++a)
      for (int b = 0; b < dim; ++b) {
        T[i](a, b) = (a == b ? 1.0 : 0.0) + 0.2 * u(rng);
        dT[i](a, b) = step * u(rng);
      }
    if (every > 0 && i % every == 0) dT[i] *= every_factor;
  }
  double best = 1e300, sink = 0.0;
  for (int pass = 0; pass < 7; ++pass) {
    Kokkos::Timer t;
    double acc = 0.0;
    for (int i = 0; i < n; ++i) acc += std::min(smallest_positive_det_root<dim>(T[i], dT[i], 1.0 / 0.9), 10.0);
    best = std::min(best, t.seconds());
    sink += acc;
  }
  if (sink == 12345.678) std::cout << "";  // keep the work
  return best / n * 1e9;
}

template <int dim>
void run(int n) {
  std::cout << dim << "D: small " << ns_per_stencil<dim>(n, 1e-3, 0, 1.0) << " ns, large "
            << ns_per_stencil<dim>(n, 1.0, 0, 1.0) << " ns, mixed " << ns_per_stencil<dim>(n, 1e-3, 50, 1e3)
            << " ns per stencil\n";
}

}  // namespace

int main(int argc, char** argv) {
  int n = 1000000;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--stencils") n = std::atoi(argv[i + 1]);
  run<2>(n);
  run<3>(n);
  return 0;
}
