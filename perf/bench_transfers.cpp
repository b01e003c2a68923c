// MPM transfer throughput: P2G (mass + momentum, APIC) and G2P (APIC: v, x,
// F, B) in particles per second, for 1e4, 1e5, 1e6 particles in 2D and 1e5 in
// 3D, beside the memory bandwidth of a plain copy kernel measured in the same
// run. Threads follow OMP_NUM_THREADS (perf/run_transfers.sh runs 1 and 2).
// Writes JSON:  bench_transfers [--out FILE]
#include <Kokkos_Core.hpp>
#include <Kokkos_Timer.hpp>
#include <Tpetra_Core.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mpi.h>
#include <sstream>
#include <string>

#include "kernels/mpm_transfer.hpp"
#include "mpm/sampling.hpp"

using namespace bfemp;

namespace {

// Best-of-5 seconds of f().
template <class F>
double best_time(F&& f) {
  double best = 1e300;
  for (int r = 0; r < 5; ++r) {
    Kokkos::fence();
    Kokkos::Timer t;
    f();
    Kokkos::fence();
    best = std::min(best, t.seconds());
  }
  return best;
}

double copy_bandwidth_GBs() {
  const std::size_t n = 1 << 25;  // 256 MiB per array
  Kokkos::View<double*, MemSpace> a("a", n), b("b", n);
  Kokkos::deep_copy(a, 1.0);
  const double s = best_time([&] {
    Kokkos::parallel_for("copy", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const std::size_t i) { b(i) = a(i); });
  });
  return 2.0 * n * sizeof(double) / s / 1e9;
}

template <int dim>
std::string bench(std::size_t target, double bw) {
  // Square/cube block with 4 (2D) or 8 (3D) particles per cell and the cell
  // count that gives ~target particles.
  const int ppc = dim == 2 ? 4 : 8;
  const double cells = static_cast<double>(target) / ppc;
  const double side = 1.0;
  const double dx = side / std::pow(cells, 1.0 / dim);
  SamplingShape shape;
  shape.kind = "box";
  shape.center = std::vector<double>(dim, 0.5);
  shape.size = std::vector<double>(dim, side);
  auto p = sample_particles<dim>(shape, dx, ppc, 1000.0, 0, 0);
  const auto grid = grid_covering<dim>(Vec<dim>::Constant(-0.1), Vec<dim>::Constant(1.1), dx);
  Kokkos::View<LO*, MemSpace> system_node("sn", grid.num_nodes()), grid_node;
  const LO n_active = activate_grid<dim>(grid, p, 0, system_node, grid_node);
  Kokkos::View<double*, MemSpace> mass("m", n_active), mom("mv", n_active * dim);
  GridScatter ms(mass), vs(mom);  // the production path's scatter (MpmBodies::begin_step)
  const double t_p2g = best_time([&] {
    Kokkos::deep_copy(mass, 0.0);
    Kokkos::deep_copy(mom, 0.0);
    ms.reset();
    vs.reset();
    p2g(grid, p, TransferScheme::APIC, system_node, 0, ms, vs);
    Kokkos::Experimental::contribute(mass, ms);
    Kokkos::Experimental::contribute(mom, vs);
  });
  Kokkos::View<double*, MemSpace> x("x", n_active * dim), v("v", n_active * dim), v0("v0", n_active * dim);
  Kokkos::parallel_for(
      "grid_x", Kokkos::RangePolicy<ExecSpace>(0, n_active), KOKKOS_LAMBDA(const LO k) {
        const Vec<dim> xi = grid.node_position(grid_node(k));
        for (int c = 0; c < dim; ++c) x(k * dim + c) = xi(c);
      });
  auto p_copy = allocate_particles<dim>(p.size());
  const double t_g2p = best_time([&] {
    Kokkos::deep_copy(p_copy.x, p.x);  // G2P moves particles: restart from the same state
    Kokkos::deep_copy(p_copy.F, p.F);
    g2p(grid, p_copy, TransferScheme::APIC, system_node, x, v, v0);
  });
  const double t_copy_state = best_time([&] {
    Kokkos::deep_copy(p_copy.x, p.x);
    Kokkos::deep_copy(p_copy.F, p.F);
  });
  const double g2p_s = std::max(t_g2p - t_copy_state, 1e-12);
  // Bytes a transfer must at least move per particle: P2G reads x, v, C, mass
  // (dim + dim + dim^2 + 1 doubles); G2P reads x, F and writes x, v, F, C.
  const double p2g_bytes = (2.0 * dim + dim * dim + 1) * 8, g2p_bytes = (3.0 * dim + 3.0 * dim * dim) * 8;
  const double np = static_cast<double>(p.size());
  std::ostringstream j;
  j << "{\"dim\": " << dim << ", \"particles\": " << p.size() << ", \"active_nodes\": " << n_active
    << ", \"p2g_s\": " << t_p2g << ", \"g2p_s\": " << g2p_s << ", \"p2g_particles_per_s\": " << np / t_p2g
    << ", \"g2p_particles_per_s\": " << np / g2p_s
    << ", \"p2g_fraction_of_bandwidth\": " << np * p2g_bytes / t_p2g / 1e9 / bw
    << ", \"g2p_fraction_of_bandwidth\": " << np * g2p_bytes / g2p_s / 1e9 / bw << "}";
  std::cout << "  " << dim << "D " << p.size() << " particles: P2G " << np / t_p2g / 1e6 << " M/s, G2P "
            << np / g2p_s / 1e6 << " M/s (bandwidth fractions " << np * p2g_bytes / t_p2g / 1e9 / bw << ", "
            << np * g2p_bytes / g2p_s / 1e9 / bw << ")\n"
            << std::flush;
  return j.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "transfers.json";
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--out") out = argv[i + 1];
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  {
    Kokkos::InitArguments ka;
    if (const char* s = std::getenv("OMP_NUM_THREADS")) ka.num_threads = std::atoi(s);
    Kokkos::ScopeGuard kokkos(ka);
    Tpetra::ScopeGuard tpetra(&argc, &argv);
    const int threads = Kokkos::DefaultExecutionSpace::concurrency();
    const double bw = copy_bandwidth_GBs();
    std::cout << "bench_transfers: " << threads << " thread(s), copy bandwidth " << bw << " GB/s\n";
    std::ostringstream j;
    j << "{\"threads\": " << threads << ", \"copy_bandwidth_GBs\": " << bw << ", \"cases\": [";
    j << bench<2>(10000, bw) << ", " << bench<2>(100000, bw) << ", " << bench<2>(1000000, bw) << ", "
      << bench<3>(100000, bw) << "]}\n";
    std::ofstream(out) << j.str();
  }
  MPI_Finalize();
  return 0;
}
