// Barrier contact costs (2D): a strip of FEM triangles whose top edge carries
// ~n_facets boundary edges, under a layer of n_particles MPM particles whose
// first rows lie within dhat. Per case: broad phase (static pairs at x and
// swept pairs along a direction), pair evaluation (barrier gradient + PSD
// Hessian assembled into a Tpetra matrix) in active pairs per second, the
// lagged friction term's gradient + Hessian over the same pairs (mu 0.5,
// every pair static), and the CCD step bound over the swept pairs. Threads follow OMP_NUM_THREADS
// (perf/run_contact.sh runs 1 and 2).   Writes JSON:  bench_contact [--out FILE]
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

#include "contact/contact.hpp"
#include "solver/dof_graph.hpp"

using namespace bfemp;

namespace {

template <class F>
double best_time(F&& f) {
  double best = 1e300;
  for (int r = 0; r < 3; ++r) {
    Kokkos::fence();
    Kokkos::Timer t;
    f();
    Kokkos::fence();
    best = std::min(best, t.seconds());
  }
  return best;
}

std::string bench(long n_particles, long n_facets) {
  const int rows = 10;
  const long cols = n_particles / rows;
  const double hp = 0.01, dhat = 2.5 * hp, L = cols * hp;
  // FEM strip [0, L] x [-0.1, 0]: n_facets/2 columns of 2 triangles.
  const long nc = std::max(1L, n_facets / 2);
  MeshData m;
  m.dim = 2;
  for (long i = 0; i <= nc; ++i) {
    m.coords.insert(m.coords.end(), {L * i / nc, -0.1});
    m.coords.insert(m.coords.end(), {L * i / nc, 0.0});
  }
  for (long i = 0; i < nc; ++i) {
    const long a = 2 * i, b = 2 * i + 2, c = 2 * i + 3, d = 2 * i + 1;
    m.cells.insert(m.cells.end(), {a, b, c, a, c, d});
  }
  MaterialParams mp;
  mp.lame = lame_from_young(1e6, 0.3);
  mp.density = 1000;
  std::vector<FemBodyInput> bodies{{"strip", m, 0}};
  FemMesh<2> mesh = build_fem_mesh<2>(bodies, {mp});
  MpmSetup<2> ms;
  const double dx = 2 * hp;
  ms.grid = grid_covering<2>(Vec<2>(-4 * dx, -4 * dx), Vec<2>(L + 4 * dx, rows * hp + 4 * dx), dx);
  ms.particles = allocate_particles<2>(cols * rows);
  auto p = ms.particles;
  Kokkos::parallel_for(
      "bench_particles", Kokkos::RangePolicy<ExecSpace>(0, cols * rows), KOKKOS_LAMBDA(const long q) {
        p.x(q, 0) = (q % cols + 0.5) * hp;
        p.x(q, 1) = (q / cols + 0.5) * hp;
        p.volume0(q) = hp * hp;
        p.mass(q) = 1000 * hp * hp;
      });
  ms.body_names = {"layer"};
  MpmBodies<2> mpm(ms, mesh.elements.materials);
  const LO nF = mesh.num_nodes(), nA = mpm.begin_step(nF, 1), nn = nF + nA;
  Kokkos::View<double*, MemSpace> x("x", nn * 2), v("v", nn * 2), mass("m", nn * 2), dir("p", nn * 2);
  Kokkos::deep_copy(Kokkos::subview(x, std::make_pair(0, nF * 2)), mesh.rest_position);
  mpm.fill_system(x, v, mass);
  Kokkos::parallel_for(
      "bench_dir", Kokkos::RangePolicy<ExecSpace>(0, nn * 2), KOKKOS_LAMBDA(const LO i) {
        dir(i) = (i % 2 == 1 && i >= nF * 2) ? -0.4 * hp : 0.1 * hp;  // grid moves down toward the strip
      });
  ContactParams cp;
  cp.dhat = dhat;
  cp.kappa = 1e5;
  cp.mu = {0.5};
  Contact<2> contact(mesh, cp);
  contact.begin_step(mpm, x);
  auto* barrier = contact.barrier();
  const double t_broad = best_time([&] { barrier->update(x); });
  const LO candidates = barrier->candidate_pairs();
  const LO active = barrier->active_pairs(x).count;
  barrier->update(x);
  // Friction lagged at x against x shifted along the strip, grid and strip
  // alike: the relative slide cancels, so every pair is in the static
  // (mollified) branch, whose tangent Hessian is not zero (in 2D the sliding
  // branch's is: f1' = 0), the costlier case to assemble.
  Kokkos::View<double*, MemSpace> xref("xref", nn * 2);
  Kokkos::parallel_for(
      "bench_xref", Kokkos::RangePolicy<ExecSpace>(0, nn * 2), KOKKOS_LAMBDA(const LO i) {
        xref(i) = x(i) - (i % 2 == 0 ? 0.05 * hp : 0.0);
      });
  const LO friction_pairs = contact.update_friction(x, xref, 1.0, 1e-3);
  const auto* friction = contact.friction();
  auto map = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(nn * 2), 0, Tpetra::getDefaultComm()));
  auto A = Teuchos::rcp(new Matrix(build_dof_graph<2>({barrier, friction}, nn, map)));
  A->fillComplete();
  Kokkos::View<double*, MemSpace> grad("g", nn * 2), rhs("r", nn * 2), dxp("dxp", nn * 2);
  Kokkos::View<int*, MemSpace> pres("pres", nn * 2);
  A->resumeFill();
  const auto lcl = A->getLocalMatrixDevice();
  const double t_eval = best_time([&] { barrier->assemble(x, make_sink<2>(lcl, 1.0, grad, rhs, pres, dxp)); });
  const double t_friction = best_time([&] { friction->assemble(x, make_sink<2>(lcl, 1.0, grad, rhs, pres, dxp)); });
  const double t_swept = best_time([&] { barrier->prepare_direction(x, dir); });
  const LO swept = barrier->candidate_pairs();
  double alpha = 0;
  const double t_ccd = best_time([&] { alpha = barrier->max_step(x, dir); });
  std::ostringstream j;
  j << "{\"particles\": " << cols * rows << ", \"boundary_primitives\": " << barrier->primitives().size()
    << ", \"facets\": " << barrier->primitives().num_facets << ", \"candidate_pairs\": " << candidates
    << ", \"active_pairs\": " << active << ", \"broad_phase_s\": " << t_broad << ", \"eval_s\": " << t_eval
    << ", \"pairs_per_s\": " << active / t_eval << ", \"friction_pairs\": " << friction_pairs
    << ", \"friction_s\": " << t_friction << ", \"swept_pairs\": " << swept
    << ", \"swept_broad_phase_s\": " << t_swept << ", \"ccd_s\": " << t_ccd << ", \"ccd_alpha\": " << alpha << "}";
  std::cout << "  " << cols * rows << " particles, " << barrier->primitives().num_facets << " facets: broad phase "
            << t_broad * 1e3 << " ms (" << candidates << " candidates, " << active << " active), gradient+Hessian "
            << t_eval * 1e3 << " ms (" << active / t_eval / 1e6 << " M pairs/s), friction " << t_friction * 1e3
            << " ms (" << friction_pairs << " pairs), swept broad phase " << t_swept * 1e3
            << " ms (" << swept << "), CCD " << t_ccd * 1e3 << " ms (alpha " << alpha << ")\n"
            << std::flush;
  return j.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "contact.json";
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
    std::cout << "bench_contact: " << threads << " thread(s)\n";
    std::ostringstream j;
    j << "{\"threads\": " << threads << ", \"cases\": [" << bench(10000, 1000) << ", " << bench(10000, 10000) << ", "
      << bench(100000, 1000) << ", " << bench(100000, 10000) << "]}\n";
    std::ofstream(out) << j.str();
  }
  MPI_Finalize();
  return 0;
}
