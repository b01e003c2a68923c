// Assembly kernels per stencil, the rows of the speed issue's table:
//   mpm_cells         MPM elasticity by cell and color, no atomics (what the
//                     simulation runs): gradient + PSD 3^d-node Hessian into
//                     the matrix, per particle;
//   mpm_per_particle  the same stencils one particle at a time with atomics
//                     (the generic deformation_assemble path), per particle;
//   fem               FEM simplices (triangles / tetrahedra): gradient +
//                     projected (d+1)d square Hessian into the matrix, per
//                     element, colored without atomics (what the simulation runs);
//   mpm_cells_search, fem_search  the same without the scatter table: every
//                     3x3 (2x2) block found by bisection in its row;
//   fem_atomic        the same, all elements at once with atomic adds;
//                     (on 1 thread both rows run all elements in index order
//                     without atomics: DeformationTerm::assemble)
// beside a STREAM-style copy (GB/s) measured in the same run, so that a slow
// machine shows as a slow copy too. Each figure is the best of 5 calls on a
// matrix from the DOF space (solver/dof_space.hpp), as the Newton solver
// assembles it. Prints ns per item and the ratio to the goal.
//   bench_assembly [--out assembly.json] [--quick]
// Run at 1 and 2 threads with perf/run_benchmarks.sh --bench bench_assembly;
// compare with perf/compare.py --baseline perf/baselines/assembly.json
// --fields per_item_s.
#include <Kokkos_Core.hpp>
#include <Kokkos_Timer.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mpi.h>
#include <string>
#include <vector>

#include "bench_json.hpp"
#include "fem/fem_mesh.hpp"
#include "io/shape_mesher.hpp"
#include "materials/lame.hpp"
#include "mpm/mpm_bodies.hpp"
#include "mpm/sampling.hpp"
#include "solver/dof_space.hpp"

using namespace bfemp;
using namespace bfemp::bench;

namespace {

template <class Fn>
double best_of(int reps, Fn&& fn) {
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    Kokkos::fence();
    Kokkos::Timer t;
    fn();
    Kokkos::fence();
    best = std::min(best, t.seconds());
  }
  return best;
}

// GB/s of b = a over n doubles (read + write counted).
double stream_copy_gbs() {
  const std::size_t n = 20'000'000;
  Kokkos::View<double*, MemSpace> a("a", n), b("b", n);
  Kokkos::deep_copy(a, 1.0);
  const double t = best_of(5, [&] {
    Kokkos::parallel_for("stream_copy", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const std::size_t i) { b(i) = a(i); });
  });
  return 2.0 * n * sizeof(double) / t / 1e9;
}

struct Sys {
  Kokkos::View<double*, MemSpace> grad, rhs, dxp;
  Kokkos::View<int*, MemSpace> pres;
  explicit Sys(std::size_t nd) : grad("grad", nd), rhs("rhs", nd), dxp("dxp", nd), pres("pres", nd) {}
};

// tabled: the sink carries the scatter table of the space's only term (as
// the Newton solver hands it over); otherwise every block is found by bisection.
template <int dim>
double time_assembly(DofSpace<dim>& space, const std::function<void(const Sink<dim>&)>& assemble, bool tabled = true) {
  Sys s(space.num_dofs());
  return best_of(5, [&] {
    space.begin_assembly();
    const Sink<dim> sink = space.sink(1.0, s.grad, s.rhs, s.pres, s.dxp);
    assemble(tabled ? space.term_sink(sink, 0) : sink);
  });
}

Json row(int dim, const std::string& kind, long long items, double seconds, double goal_ns) {
  const int threads = Kokkos::DefaultExecutionSpace::concurrency();
  const double ns = seconds / items * 1e9;
  std::cout << "  " << dim << "D " << kind << ": " << items << " items, " << seconds * 1e3 << " ms, " << ns
            << " ns per item (goal " << goal_ns << " ns at 1 thread: " << ns / goal_ns << "x)\n"
            << std::flush;
  return Json()
      .integer("dim", dim)
      .str("size", std::to_string(items))
      .str("solver", kind)
      .integer("threads", threads)
      .integer("items", items)
      .num("assembly_s", seconds)
      .num("per_item_s", seconds / items)
      .num("goal_per_item_s", goal_ns * 1e-9);
}

template <int dim>
void mpm_rows(double target, std::vector<Json>& out, const Teuchos::RCP<const Comm>& comm) {
  const int ppc = dim == 2 ? 4 : 8;
  const double dx = 1.0 / std::round(std::pow(target / ppc, 1.0 / dim));
  SamplingShape shape;
  shape.kind = "box";
  shape.center = std::vector<double>(dim, 0.5);
  shape.size = std::vector<double>(dim, 1.0);
  MpmSetup<dim> m;
  m.particles = sample_particles<dim>(shape, dx, ppc, 1000.0, 0, 0);
  m.grid = grid_covering<dim>(Vec<dim>::Constant(-0.1), Vec<dim>::Constant(1.2), dx);
  // Some deformation, so that the tangent projection has work to do.
  auto F = m.particles.F;
  Kokkos::parallel_for(
      "bench_F", Kokkos::RangePolicy<ExecSpace>(0, m.particles.size()), KOKKOS_LAMBDA(const LO q) {
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) F(q, i, j) = (i == j ? 0.9 : 0.0) + 0.05 * std::sin(1.0 + q + 3 * i + 7 * j);
      });
  Kokkos::View<MaterialParams*, MemSpace> mats("mats", 1);
  mats(0) = MaterialParams{MaterialModel::NeoHookean, lame_from_young(1e6, 0.3), 1000.0};
  MpmBodies<dim> mpm(m, mats);
  const LO n = mpm.begin_step(0, 1);
  const std::size_t nd = static_cast<std::size_t>(n) * dim;
  Kokkos::View<double*, MemSpace> x("x", nd), v("v", nd), mass("m", nd);
  mpm.fill_system(x, v, mass);
  DofSpace<dim> space(comm);
  space.set_structure(n, {&mpm.term()});
  const long long np = static_cast<long long>(m.particles.size());
  const auto& term = mpm.term();
  const double goal = dim == 2 ? 1500.0 : 15000.0;  // 2D: not in the table; 1/10 of 3D's
  out.push_back(row(dim, "mpm_cells", np, time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble(x, s); }), goal));
  out.push_back(row(dim, "mpm_cells_search", np,
                    time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble(x, s); }, false), goal));
  out.push_back(row(dim, "mpm_per_particle", np,
                    time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble_per_particle(x, s); }), goal));
}

template <int dim>
void fem_rows(double h, std::vector<Json>& out, const Teuchos::RCP<const Comm>& comm) {
  ShapeSpec spec;
  spec.kind = dim == 2 ? "rectangle" : "box";
  spec.center = std::vector<double>(dim, 0.5);
  spec.size = std::vector<double>(dim, 1.0);
  spec.element_size = h;
  FemBodyInput body;
  body.name = "block";
  body.mesh = mesh_shape(spec, dim);
  std::vector<MaterialParams> mats{MaterialParams{MaterialModel::NeoHookean, lame_from_young(1e6, 0.3), 1000.0}};
  FemMesh<dim> mesh = build_fem_mesh<dim>({body}, mats);
  const std::size_t nd = static_cast<std::size_t>(mesh.num_nodes()) * dim;
  Kokkos::View<double*, MemSpace> x("x", nd);
  auto X = mesh.rest_position;
  Kokkos::parallel_for(
      "bench_fem_x", Kokkos::RangePolicy<ExecSpace>(0, nd), KOKKOS_LAMBDA(const std::size_t i) {
        x(i) = X(i) * (i % dim == 0 ? 0.92 : 1.05) + 1e-3 * std::sin(3.0 * i);
      });
  DeformationTerm<dim, dim + 1> term("fem", mesh.elements);
  DofSpace<dim> space(comm);
  space.set_structure(mesh.num_nodes(), {&term});
  const double goal = dim == 2 ? 1000.0 : 2500.0;  // 2D: not in the table
  out.push_back(row(dim, "fem_atomic", mesh.num_cells(),
                    time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble(x, s); }), goal));
  term.set_coloring(color_stencils<dim + 1>(mesh.elements.nodes, mesh.num_nodes()));  // as the simulation runs it
  out.push_back(row(dim, "fem", mesh.num_cells(), time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble(x, s); }), goal));
  out.push_back(row(dim, "fem_search", mesh.num_cells(),
                    time_assembly<dim>(space, [&](const Sink<dim>& s) { term.assemble(x, s); }, false), goal));
}

}  // namespace

int main(int argc, char** argv) {
  BenchArgs args{"assembly.json"};
  if (const int bad = parse_bench_args(argc, argv, "bench_assembly", args)) return bad;
  const bool quick = args.quick;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    Kokkos::ScopeGuard kokkos(kokkos_args_from_env());
    Tpetra::ScopeGuard tpetra(&argc, &argv);
    auto comm = Tpetra::getDefaultComm();
    const int threads = Kokkos::DefaultExecutionSpace::concurrency();
    std::cout << "bench_assembly: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", " << threads
              << " thread(s)\n";
    const double gbs = stream_copy_gbs();
    std::cout << "  STREAM-style copy: " << gbs << " GB/s\n";
    std::vector<Json> results;
    mpm_rows<2>(quick ? 1e4 : 1e5, results, comm);
    mpm_rows<3>(quick ? 2e3 : 2e4, results, comm);
    fem_rows<2>(quick ? 0.03 : 0.005, results, comm);
    fem_rows<3>(quick ? 0.1 : 0.035, results, comm);
    for (auto& r : results) r.num("stream_copy_gbs", gbs);
    Json top;
    top.str("benchmark", "assembly")
        .integer("threads", threads)
        .str("kokkos_backend", Kokkos::DefaultExecutionSpace::name())
        .num("stream_copy_gbs", gbs)
        .raw("scene", Json()
                          .str("mpm", "unit square/cube of particles (4/8 per cell), F = 0.9 I + 0.05 sin(..)")
                          .str("fem", "unit square/cube meshed by Gmsh, x = stretched rest positions")
                          .str("material", "neo-Hookean, E = 1e6 Pa, nu = 0.3")
                          .dump(2))
        .raw("results", jarray(results, 4));
    code = write_json(top, args.out, "bench_assembly");
  }
  MPI_Finalize();
  return code;
}
