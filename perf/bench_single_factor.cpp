// The triangular solves of CG on the previous factor (SingleFactor::solve, the
// float copy of a supernodal CHOLMOD factor) on 1 thread and on the host's
// threads, for a 3D elasticity-like matrix: a 27-point stencil on side^3 grid
// nodes, 3 DOFs per node coupled in a 3x3 block, diagonally dominant (SPD).
// side 30 has 81000 DOFs and about as many stored factor entries per DOF as
// the paper twist's Newton matrix (3.7e7 entries for ~3.3e5 DOFs there).
//
// Per size: the factor's entries, the schedule (subtrees, top supernodes, the
// top's share of the entries), and the best of --repeats solves at 1 thread
// and at OMP_NUM_THREADS (solve_1_s, solve_s, speedup), with the GB/s of
// the factor read (8 bytes per entry: the forward and backward passes read
// each float once each).
//
//   bench_single_factor [--quick] [--out FILE]
// Writes JSON (default single_factor.json) whose "results" perf/compare.py
// matches on (dim, size, solver, threads); see perf/README.md.
#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

#include "bench_json.hpp"
#include "solver/cholmod_views.hpp"
#include "solver/single_factor.hpp"

using namespace bfemp;
using namespace bfemp::bench;

namespace {

using Long = SuiteSparse_long;

struct Csc {
  std::vector<Long> p, i;
  std::vector<double> x;
};

// Upper triangle by columns (CHOLMOD's stype = 1): node blocks
// K_ab = (a == b ? 30 : -1) I3 + (a == b ? 0.5 : -0.1) (ones - I3)/2 for the
// 27 neighbours b of a (each within one step on every axis).
Csc elasticity_like(int side) {
  const int nn = side * side * side;
  Csc a;
  a.p.push_back(0);
  for (int col = 0; col < 3 * nn; ++col) {
    const int node = col / 3, c = col % 3;
    const int x = node % side, y = (node / side) % side, z = node / (side * side);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int X = x + dx, Y = y + dy, Z = z + dz;
          if (X < 0 || Y < 0 || Z < 0 || X >= side || Y >= side || Z >= side) continue;
          const int other = X + side * (Y + side * Z);
          const bool self = other == node;
          for (int r = 0; r < 3; ++r) {
            const int row = 3 * other + r;
            if (row > col) continue;
            a.i.push_back(row);
            a.x.push_back(r == c ? (self ? 30.0 : -1.0) : (self ? 0.25 : -0.05));
          }
        }
    a.p.push_back(static_cast<Long>(a.i.size()));
  }
  return a;
}

template <class F>
double best_of(int repeats, F&& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

Json size_row(int side, int threads, int repeats) {
  Csc a = elasticity_like(side);
  cholmod_sparse S = symmetric_csc_view(a.p, a.i, a.x.data());
  cholmod_common c{};
  cholmod_l_start(&c);
  c.print = 0;
  c.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_factor* L = cholmod_l_analyze(&S, &c);
  cholmod_l_factorize(&S, L, &c);
  Json row;
  SingleFactor f;
  if (c.status != CHOLMOD_OK || !f.assign(*L)) {
    std::cerr << "bench_single_factor: side " << side << ": factorisation or copy failed\n";
    cholmod_l_free_factor(&L, &c);
    cholmod_l_finish(&c);
    return row;
  }
  const std::size_t n = L->n;
  std::vector<double> b(n), z(n);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (double& v : b) v = g(rng);
  const double t1 = best_of(repeats, [&] { f.solve(b.data(), z.data(), 1); });
  const double tt = threads > 1 ? best_of(repeats, [&] { f.solve(b.data(), z.data(), threads); }) : t1;
  const auto& s = f.schedule();
  int shared = 0;
  for (char k : s.top_shared) shared += k;
  const double bytes = 8.0 * static_cast<double>(f.entries());
  std::cout << "  side " << side << ": " << n << " DOFs, " << f.entries() << " factor entries; solve " << t1 * 1e3
            << " ms at 1 thread, " << tt * 1e3 << " ms at " << threads << " (" << t1 / tt << "x; " << s.order.size()
            << " subtrees, " << s.top.size() << " top supernodes, " << shared << " shared, top "
            << s.top_fraction << " of the entries)\n";
  row.integer("dim", 3)
      .integer("size", static_cast<long long>(n))
      .str("solver", "single_factor_solve")
      .integer("threads", threads)
      .integer("factor_entries", static_cast<long long>(f.entries()))
      .integer("subtrees", static_cast<long long>(s.order.size()))
      .integer("top_supernodes", static_cast<long long>(s.top.size()))
      .integer("top_shared", shared)
      .num("top_fraction", s.top_fraction)
      .num("solve_1_s", t1)
      .num("solve_s", tt)
      .num("speedup", t1 / tt)
      .num("read_gbs", bytes / tt / 1e9);
  cholmod_l_free_factor(&L, &c);
  cholmod_l_finish(&c);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  BenchArgs args;
  args.out = "single_factor.json";
  if (const int rc = parse_bench_args(argc, argv, "bench_single_factor", args)) return rc;
  Kokkos::ScopeGuard kokkos(kokkos_args_from_env());
  const int threads = Kokkos::DefaultHostExecutionSpace().concurrency();
  std::cout << "bench_single_factor: " << threads << " thread(s)\n";
  std::vector<Json> results;
  for (int side : args.quick ? std::vector<int>{12} : std::vector<int>{16, 24, 30})
    results.push_back(size_row(side, threads, args.quick ? 3 : 10));
  Json top;
  top.str("benchmark", "single_factor")
      .integer("threads", threads)
      .str("matrix", "27-point stencil on side^3 nodes, 3 DOFs per node in 3x3 blocks, diagonally dominant")
      .raw("results", jarray(results, 4));
  return write_json(top, args.out, "bench_single_factor");
}
