// Cholmod's factor reuse (solver/cholmod_direct.hpp): CG preconditioned by the
// previous numeric factor of the same graph, or a new factorisation when CG
// cannot reach the tolerance, meets non-positive curvature, or the factor was
// forgotten. Matrices: the 2D five-point Laplacian on a 20 x 20 grid plus a
// diagonal shift (full symmetric storage, as the DOF space assembles it).
#include <gtest/gtest.h>

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "common/fem_fixtures.hpp"
#include "solver/cholmod_direct.hpp"
#include "solver/single_factor.hpp"
#include "solver/solver_error.hpp"

namespace {

using namespace bfemp;
using Teuchos::RCP;
using Teuchos::rcp;

constexpr int kSide = 20, kN = kSide * kSide;

// Laplacian + diag(shift_i); the graph is the same for every shift.
RCP<Matrix> laplacian(const std::vector<double>& shift) {
  auto map = rcp(new Map(kN, 0, fixtures::comm()));
  auto A = rcp(new Matrix(map, 5));
  for (int i = 0; i < kN; ++i) {
    const int r = i / kSide, c = i % kSide;
    std::vector<GO> cols{i};
    std::vector<double> vals{4.0 + shift[i]};
    if (c > 0) cols.push_back(i - 1), vals.push_back(-1.0);
    if (c + 1 < kSide) cols.push_back(i + 1), vals.push_back(-1.0);
    if (r > 0) cols.push_back(i - kSide), vals.push_back(-1.0);
    if (r + 1 < kSide) cols.push_back(i + kSide), vals.push_back(-1.0);
    A->insertGlobalValues(GO(i), Teuchos::ArrayView<const GO>(cols), Teuchos::ArrayView<const double>(vals));
  }
  A->fillComplete();
  return A;
}

// Overwrites A's values with those of B (same graph): the solver keeps A.
void copy_values(const Matrix& B, Matrix& A) {
  A.resumeFill();
  auto a = A.getLocalMatrixDevice().values;
  auto b = B.getLocalMatrixDevice().values;
  Kokkos::deep_copy(a, b);
  A.fillComplete();
}

double relative_residual(const Matrix& A, const Vector& x, const Vector& b) {
  Vector r(b.getMap());
  A.apply(x, r);
  r.update(1.0, b, -1.0);
  return r.norm2() / b.norm2();
}

// shift_i (1 + u_i), u_i uniform in [-spread, spread] (seed 7): a Newton-like change of the values.
std::vector<double> perturbed(std::vector<double> shift, double spread) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-spread, spread);
  for (double& s : shift) s *= 1.0 + u(rng);
  return shift;
}

struct Fixture {
  std::vector<double> shift = std::vector<double>(kN, 1.0);
  RCP<Matrix> A = laplacian(shift);
  Vector b{A->getRowMap()}, x{A->getRowMap()};
  Fixture() { b.randomize(); }
};

TEST(CholmodReuse, NearbyValuesAreSolvedByCgOnThePreviousFactor) {
  Fixture f;
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  const auto first = solver.solve(f.b, f.x);
  EXPECT_TRUE(first.analysed);
  EXPECT_TRUE(first.factorised);
  EXPECT_EQ(first.cg_iterations, 0);
  EXPECT_LT(relative_residual(*f.A, f.x, f.b), 1e-13);

  // A Newton-like change: the shift moves by up to 5 %.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  auto s2 = f.shift;
  for (double& s : s2) s *= 1.0 + u(rng);
  copy_values(*laplacian(s2), *f.A);
  const auto second = solver.solve(f.b, f.x);
  EXPECT_FALSE(second.factorised);
  EXPECT_FALSE(second.analysed);
  EXPECT_GE(second.cg_iterations, 1);
  EXPECT_LE(second.cg_iterations, 20);
  EXPECT_LT(relative_residual(*f.A, f.x, f.b), 1e-10);

  // The same system factorised anew gives the same x to the CG tolerance.
  CholmodDirect direct(CholmodReuse{0, 1e-10});
  direct.set_matrix(f.A);
  Vector xd(f.A->getRowMap());
  EXPECT_TRUE(direct.solve(f.b, xd).factorised);
  Vector d(f.A->getRowMap());
  d.update(1.0, f.x, -1.0, xd, 0.0);
  EXPECT_LT(d.norm2() / xd.norm2(), 1e-9);

  // forget_factor (a new time step): the next solve factorises.
  solver.forget_factor();
  const auto third = solver.solve(f.b, f.x);
  EXPECT_TRUE(third.factorised);
  EXPECT_EQ(third.cg_iterations, 0);
}

// An inexact Newton direction: CG on the previous factor stops at the
// tolerance the caller allows, not the reuse tolerance, and says which it
// reached; a factorisation's solve reports 0 (exact); a tolerance below the
// reuse tolerance does not tighten it.
TEST(CholmodReuse, ALooserToleranceStopsCgEarlierAndIsReported) {
  Fixture f;
  const auto s2 = perturbed(f.shift, 0.3);
  auto solve_at = [&](double tol, CholmodDirect::Result& r, Vector& x) {
    CholmodDirect solver(CholmodReuse{20, 1e-10});
    solver.set_matrix(f.A);
    copy_values(*laplacian(f.shift), *f.A);
    const auto first = solver.solve(f.b, x, tol);
    EXPECT_TRUE(first.factorised);
    EXPECT_EQ(first.tolerance, 0.0);
    copy_values(*laplacian(s2), *f.A);
    r = solver.solve(f.b, x, tol);
  };
  CholmodDirect::Result tight, loose, below;
  Vector xt(f.A->getRowMap()), xl(f.A->getRowMap()), xb(f.A->getRowMap());
  solve_at(0.0, tight, xt);
  solve_at(1e-3, loose, xl);
  solve_at(1e-14, below, xb);
  ASSERT_FALSE(tight.factorised);
  ASSERT_FALSE(loose.factorised);
  ASSERT_FALSE(below.factorised);
  EXPECT_EQ(tight.tolerance, 1e-10);
  EXPECT_EQ(loose.tolerance, 1e-3);
  EXPECT_EQ(below.tolerance, 1e-10);
  EXPECT_EQ(below.cg_iterations, tight.cg_iterations);
  EXPECT_LT(loose.cg_iterations, tight.cg_iterations);
  EXPECT_GE(loose.cg_iterations, 1);
  EXPECT_LT(relative_residual(*f.A, xt, f.b), 1e-10);
  const double rl = relative_residual(*f.A, xl, f.b);
  EXPECT_LT(rl, 1e-3);
  EXPECT_GT(rl, 1e-10);  // it did stop early
  std::printf("  CG on the previous factor: %d iterations to 1e-10, %d to 1e-3 (residual %.2e)\n",
              tight.cg_iterations, loose.cg_iterations, rl);
}

// Newton's confirming solve: CG on the previous factor goes on from the loose
// solution (from_x) and reaches the tight tolerance, relative to |b| as a
// cold solve, in fewer iterations than a cold solve; the answers agree to
// that tolerance. A starting x that already meets the tolerance costs no
// iteration and is returned as it is.
TEST(CholmodReuse, TheConfirmingSolveGoesOnFromTheLooseSolution) {
  Fixture f;
  const auto s2 = perturbed(f.shift, 0.3);
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  ASSERT_TRUE(solver.solve(f.b, f.x).factorised);
  copy_values(*laplacian(s2), *f.A);
  Vector x(f.A->getRowMap());
  const auto loose = solver.solve(f.b, x, 1e-3);
  ASSERT_FALSE(loose.factorised);
  const double rl = relative_residual(*f.A, x, f.b);
  ASSERT_LT(rl, 1e-3);
  ASSERT_GT(rl, 1e-10);
  const auto warm = solver.solve(f.b, x, 0.0, /*from_x=*/true);
  Vector xc(f.A->getRowMap());
  xc.putScalar(123.0);  // ignored without from_x
  const auto cold = solver.solve(f.b, xc, 0.0);
  ASSERT_FALSE(warm.factorised);
  ASSERT_FALSE(cold.factorised);
  EXPECT_EQ(warm.tolerance, 1e-10);
  EXPECT_LT(relative_residual(*f.A, x, f.b), 1e-10);
  EXPECT_LT(relative_residual(*f.A, xc, f.b), 1e-10);
  EXPECT_LT(warm.cg_iterations, cold.cg_iterations);
  EXPECT_GE(warm.cg_iterations, 1);
  Vector d(f.A->getRowMap());
  d.update(1.0, x, -1.0, xc, 0.0);
  EXPECT_LT(d.norm2() / xc.norm2(), 1e-8);
  // Already converged: nothing to do, x untouched.
  Vector keep(x, Teuchos::Copy);
  const auto none = solver.solve(f.b, x, 0.0, true);
  EXPECT_FALSE(none.factorised);
  EXPECT_EQ(none.cg_iterations, 0);
  d.update(1.0, x, -1.0, keep, 0.0);
  EXPECT_EQ(d.normInf(), 0.0);
  std::printf("  confirming solve to 1e-10: %d CG iterations from the 1e-3 solution, %d from 0\n",
              warm.cg_iterations, cold.cg_iterations);
}

TEST(CholmodReuse, FarValuesAreFactorisedAnew) {
  Fixture f;
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  solver.solve(f.b, f.x);
  // Shifts spread over six decades: the old factor is a poor preconditioner.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  auto s2 = f.shift;
  for (double& s : s2) s = std::pow(10.0, u(rng));
  copy_values(*laplacian(s2), *f.A);
  const auto r = solver.solve(f.b, f.x);
  EXPECT_TRUE(r.factorised);
  EXPECT_GE(r.cg_iterations, 1);  // it tried, and gave up
  EXPECT_LE(r.cg_iterations, 20);
  EXPECT_LT(relative_residual(*f.A, f.x, f.b), 1e-12);
}

TEST(CholmodReuse, AnIndefiniteMatrixIsReportedNotSolvedByCg) {
  // Diagonal 4 + shift, off-diagonals -1: eigenvalues in (shift + 0.044,
  // shift + 7.96). A shift of -0.1 leaves one negative eigenvalue.
  Fixture f;
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  solver.solve(f.b, f.x);
  copy_values(*laplacian(std::vector<double>(kN, -0.1)), *f.A);
  EXPECT_THROW(solver.solve(f.b, f.x), NotPositiveDefinite);
  // Definite again (the projected Hessian, here the first matrix): solved,
  // by CG on the factor that survived or by a new factorisation.
  copy_values(*laplacian(f.shift), *f.A);
  solver.solve(f.b, f.x);
  EXPECT_LT(relative_residual(*f.A, f.x, f.b), 1e-10);
}

// Without reuse too: a mildly indefinite matrix is refused. CHOLMOD factorises
// this small, sparse matrix simplicially; as LDL' that reported only an exact
// zero pivot and passed every shift but -6.
TEST(CholmodReuse, MildlyIndefiniteMatricesFailTheFactorisation) {
  for (double shift : {-0.1, -1.0, -5.9, -6.5}) {
    Fixture f;
    copy_values(*laplacian(std::vector<double>(kN, shift)), *f.A);
    CholmodDirect solver(CholmodReuse{0, 1e-10});
    solver.set_matrix(f.A);
    EXPECT_THROW(solver.solve(f.b, f.x), NotPositiveDefinite) << "shift " << shift;
  }
}

// After one non-positive pivot, later factorisations go into a spare: the
// next failure leaves the last good factor, and the definite solve after it
// runs CG on that factor.
TEST(CholmodReuse, AfterAFailedFactorisationTheGoodFactorSurvivesTheNext) {
  Fixture f;
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  // First failure: no factor yet (the first solve of the graph factorises).
  copy_values(*laplacian(std::vector<double>(kN, -6.5)), *f.A);
  EXPECT_THROW(solver.solve(f.b, f.x), NotPositiveDefinite);
  copy_values(*laplacian(f.shift), *f.A);
  EXPECT_TRUE(solver.solve(f.b, f.x).factorised);
  // Far, definite values: CG gives up, the factorisation goes to the spare.
  std::vector<double> far(kN);
  for (int i = 0; i < kN; ++i) far[i] = std::pow(10.0, (i % 7) - 3.0);
  copy_values(*laplacian(far), *f.A);
  EXPECT_TRUE(solver.solve(f.b, f.x).factorised);
  // Strongly indefinite, far from the factor: whichever way it is found, L survives.
  copy_values(*laplacian(std::vector<double>(kN, -6.5)), *f.A);
  EXPECT_THROW(solver.solve(f.b, f.x), NotPositiveDefinite);
  copy_values(*laplacian(far), *f.A);
  const auto r = solver.solve(f.b, f.x);
  EXPECT_FALSE(r.factorised);
  EXPECT_LE(r.cg_iterations, 2);
  EXPECT_LT(relative_residual(*f.A, f.x, f.b), 1e-10);
}

// A new graph (set_matrix) drops the factor: the next solve analyses and factorises.
TEST(CholmodReuse, ANewGraphIsAnalysedAndFactorised) {
  Fixture f;
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  solver.solve(f.b, f.x);
  EXPECT_FALSE(solver.solve(f.b, f.x).factorised);  // same values: CG, one iteration
  auto B = laplacian(f.shift);
  solver.set_matrix(B);
  const auto r = solver.solve(f.b, f.x);
  EXPECT_TRUE(r.analysed);
  EXPECT_TRUE(r.factorised);
  EXPECT_EQ(r.cg_iterations, 0);
  EXPECT_LT(relative_residual(*B, f.x, f.b), 1e-13);
}

TEST(CholmodReuse, ZeroIterationsFactorisesEverySolve) {
  Fixture f;
  CholmodDirect solver(CholmodReuse{0, 1e-10});
  solver.set_matrix(f.A);
  for (int k = 0; k < 3; ++k) {
    const auto r = solver.solve(f.b, f.x);
    EXPECT_TRUE(r.factorised);
    EXPECT_EQ(r.analysed, k == 0);
    EXPECT_EQ(r.cg_iterations, 0);
  }
}

}  // namespace

#include "common/mpm_fixtures.hpp"
#include "sim/simulation.hpp"

namespace {

// A soft MPM block falling and spinning (several Newton iterations per step):
// with reuse the run takes fewer numeric factorisations and follows the same
// trajectory to the solver tolerance (the Newton iteration counts are equal).
// A spinning MPM block falling under gravity, 6 steps. With the fixed
// forcing term, CG on the previous factor solves to 1e-10, so the Newton
// iterates are those of a factorisation at every iteration (reuse 0), to
// round-off. With the adaptive one (the default) the early directions are
// inexact: the run must still end at the same positions within what eps_d
// allows, with fewer CG iterations on the old factor.
struct SpinRun {
  long factorisations = 0, cg_iterations = 0;
  std::vector<int> its;
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> x;
};
SpinRun spin_run(int reuse, const char* forcing) {
  auto s = fixtures::mpm_block_setup(0.3, Vec<2>(0.5, 0.6), 0.05, 4, 0.0, 1.0, TransferScheme::APIC, 2e4);
  s.dt = 2e-2;
  s.gravity = {0.0, -9.81, 0.0};
  s.newton.eps_d = 1e-9;
  s.linear_solver.sublist("Cholmod").set("reuse iterations", reuse);
  s.linear_solver.sublist("Cholmod").set("forcing term", std::string(forcing));
  auto& p = s.mpm->particles;
  for (std::size_t q = 0; q < p.v.extent(0); ++q) {  // spin about the centre: 3 rad/s
    p.v(q, 0) = -3.0 * (p.x(q, 1) - 0.6);
    p.v(q, 1) = 3.0 * (p.x(q, 0) - 0.5);
  }
  Simulation<2> sim(s, fixtures::comm());
  SpinRun out;
  for (int k = 0; k < 6; ++k) {
    const auto r = sim.step();
    out.factorisations += r.newton.numeric_factorizations;
    out.cg_iterations += r.newton.reuse_cg_iterations;
    out.its.push_back(r.newton.iterations);
  }
  const auto xd = sim.mpm()->particles().x;
  out.x = Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace>("x", xd.extent(0), xd.extent(1));
  Kokkos::deep_copy(out.x, xd);
  return out;
}

double worst_difference(const SpinRun& a, const SpinRun& b) {
  double worst = 0;
  for (std::size_t q = 0; q < a.x.extent(0); ++q)
    for (int c = 0; c < 2; ++c) worst = std::fmax(worst, std::fabs(a.x(q, c) - b.x(q, c)));
  return worst;
}

TEST(CholmodReuse, SceneRunsTheSameTrajectoryWithFewerFactorisations) {
  const SpinRun r0 = spin_run(0, "fixed"), r20 = spin_run(20, "fixed");
  EXPECT_EQ(r0.its, r20.its);
  long newton = 0;
  for (int i : r0.its) newton += i;
  EXPECT_EQ(r0.factorisations, newton);
  EXPECT_LT(r20.factorisations, r0.factorisations);
  EXPECT_GE(r20.factorisations, 6);  // the first solve of every step factorises
  const double worst = worst_difference(r0, r20);
  EXPECT_LT(worst, 1e-10) << "m";
  std::printf("  Newton iterations %ld; numeric factorisations %ld (reuse 0) / %ld (reuse 20); max |dx| %.2e m\n",
              newton, r0.factorisations, r20.factorisations, worst);
}

TEST(CholmodReuse, TheAdaptiveForcingTermEndsAtTheSameStateWithFewerCgIterations) {
  const SpinRun fixed = spin_run(20, "fixed"), adaptive = spin_run(20, "adaptive");
  EXPECT_LT(adaptive.cg_iterations, fixed.cg_iterations);
  EXPECT_LE(adaptive.factorisations, fixed.factorisations);
  EXPECT_GE(adaptive.factorisations, 6);
  // eps_d 1e-9 m/s over dt 2e-2 s: the last Newton step of each solve is
  // below 2e-11 m; six steps of such differences stay far below 1e-9 m.
  const double worst = worst_difference(fixed, adaptive);
  EXPECT_LT(worst, 1e-9) << "m";
  long nf = 0, na = 0;
  for (int i : fixed.its) nf += i;
  for (int i : adaptive.its) na += i;
  std::printf("  fixed: %ld Newton iterations, %ld CG on the old factor, %ld factorisations; adaptive: %ld, %ld, %ld;"
              " max |dx| %.2e m\n",
              nf, fixed.cg_iterations, fixed.factorisations, na, adaptive.cg_iterations, adaptive.factorisations,
              worst);
}

}  // namespace

// 'reuse by cost': the CG budget rises to one factorisation's cost in CG
// iterations, F / (4 (4 |L| + 2 |A|)). For a dense n x n matrix F ~ n^3 / 3,
// |L| = n^2 (one supernode, stored as a full n x n block) and |A| = n^2, so
// the budget is about n / 72: 8 at n = 600, above the fixed budget of 2
// given here. A 5 % change of the
// diagonal then needs more than 2 CG iterations on the old factor: with the
// fixed budget the matrix is factorised anew, with the budget by cost CG
// solves it on the old factor.
namespace {
RCP<Matrix> dense_spd(int n, const std::vector<double>& diag_scale) {
  auto map = rcp(new Map(n, 0, fixtures::comm()));
  auto A = rcp(new Matrix(map, n));
  std::vector<GO> cols(n);
  for (int j = 0; j < n; ++j) cols[j] = j;
  for (int i = 0; i < n; ++i) {
    std::vector<double> vals(n);
    for (int j = 0; j < n; ++j) vals[j] = i == j ? n * diag_scale[i] : std::sin(0.37 * (i + 1) * (j + 1)) * 0.9;
    A->insertGlobalValues(GO(i), Teuchos::ArrayView<const GO>(cols), Teuchos::ArrayView<const double>(vals));
  }
  A->fillComplete();
  return A;
}
}  // namespace

TEST(CholmodReuse, TheBudgetByCostExceedsTheFixedOneForDenseFactors) {
  constexpr int n = 600;
  std::vector<double> scale(n, 1.0);
  auto perturbed = scale;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (double& s : perturbed) s *= 1.0 + u(rng);
  for (bool by_cost : {false, true}) {
    SCOPED_TRACE(by_cost ? "by cost" : "fixed");
    auto A = dense_spd(n, scale);
    Vector b(A->getRowMap()), x(A->getRowMap());
    b.randomize();
    CholmodReuse reuse{2, 1e-10};
    reuse.by_cost = by_cost;
    CholmodDirect solver(reuse);
    solver.set_matrix(A);
    EXPECT_TRUE(solver.solve(b, x).factorised);
    copy_values(*dense_spd(n, perturbed), *A);
    const auto r = solver.solve(b, x);
    EXPECT_LT(relative_residual(*A, x, b), 1e-10);
    if (by_cost) {
      EXPECT_GE(r.cg_budget, 7);
      EXPECT_LE(r.cg_budget, 9);
      EXPECT_FALSE(r.factorised) << r.cg_iterations << " CG iterations";
      EXPECT_GT(r.cg_iterations, 2);
    } else {
      EXPECT_EQ(r.cg_budget, 2);
      EXPECT_TRUE(r.factorised);
    }
  }
}

// 'reuse precision: single' (CholmodReuse::single): CG on the previous factor
// preconditions with its float copy (solver/single_factor.hpp; supernodal
// factors only, as this dense one), made once CG has run
// SingleFactor::kWorthAfterGrowing iterations on the factor in double (the
// first copy: its buffer is new). The float
// rounding (1e-7) is far below the 5 % change of the matrix since the
// factorisation, so CG on the copy takes the iterations the double factor
// takes (+-1) and reaches the same tolerance; the two answers agree to it. A
// simplicial factor (the 20 x 20 Laplacian) keeps CHOLMOD's double solve.
TEST(CholmodReuse, TheFloatCopyPreconditionsAsTheDoubleFactorDoes) {
  constexpr int n = 600;
  std::vector<double> scale(n, 1.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  auto moved = scale, moved2 = scale;
  for (double& s : moved) s *= 1.0 + u(rng);
  for (double& s : moved2) s *= 1.0 + u(rng);
  int its[2] = {0, 0};
  std::vector<Vector> answers;
  for (bool single : {false, true}) {
    SCOPED_TRACE(single ? "single" : "double");
    auto A = dense_spd(n, scale);
    Vector b(A->getRowMap()), x(A->getRowMap());
    b.putScalar(1.0);
    CholmodReuse reuse{40, 1e-12};
    reuse.single = single;
    CholmodDirect solver(reuse);
    solver.set_matrix(A);
    ASSERT_TRUE(solver.solve(b, x).factorised);
    copy_values(*dense_spd(n, moved), *A);
    const auto first = solver.solve(b, x);  // in double: the factor has served no CG yet
    ASSERT_FALSE(first.factorised);
    EXPECT_FALSE(first.cg_single);
    ASSERT_GE(first.cg_iterations, SingleFactor::kWorthAfterGrowing);
    copy_values(*dense_spd(n, moved2), *A);
    const auto r = solver.solve(b, x);
    ASSERT_FALSE(r.factorised);
    EXPECT_EQ(r.cg_single, single);
    EXPECT_LT(relative_residual(*A, x, b), 1e-12);
    its[single] = r.cg_iterations;
    answers.emplace_back(x, Teuchos::Copy);
    // A refactorisation drops the copy; a new step starts without the room the
    // last one's copies made (as a restarted run does): a factor that has
    // served fewer than kWorthAfterGrowing iterations is not copied.
    solver.forget_factor();
    ASSERT_TRUE(solver.solve(b, x).factorised);
    copy_values(*dense_spd(n, moved), *A);
    const auto loose = solver.solve(b, x, 1e-4);
    ASSERT_FALSE(loose.factorised);
    EXPECT_FALSE(loose.cg_single);
    ASSERT_GE(loose.cg_iterations, SingleFactor::kWorthAfter);
    ASSERT_LT(loose.cg_iterations, SingleFactor::kWorthAfterGrowing);
    const auto next = solver.solve(b, x);
    ASSERT_FALSE(next.factorised);
    EXPECT_FALSE(next.cg_single) << "the copy would have fitted the last step's room";
  }
  EXPECT_GE(its[0], 3);
  EXPECT_LE(std::abs(its[1] - its[0]), 1) << its[0] << " (double) against " << its[1] << " (single)";
  answers[1].update(-1.0, answers[0], 1.0);
  EXPECT_LT(answers[1].norm2() / answers[0].norm2(), 1e-10);
  EXPECT_GT(answers[1].normInf(), 0.0) << "the copy's rounding shows in the last bits: it was applied";
  std::printf("  CG on the previous factor to 1e-12: %d iterations (double factor), %d (float copy)\n", its[0],
              its[1]);
  Fixture f;  // simplicial
  CholmodDirect solver(CholmodReuse{20, 1e-10});
  solver.set_matrix(f.A);
  ASSERT_TRUE(solver.solve(f.b, f.x).factorised);
  for (double spread : {0.3, 0.2, 0.1}) {  // the later solves are past kWorthAfterGrowing
    copy_values(*laplacian(perturbed(f.shift, spread)), *f.A);
    const auto r = solver.solve(f.b, f.x);
    ASSERT_FALSE(r.factorised);
    EXPECT_FALSE(r.cg_single);
  }
}
