// The Newton line search at a friction kink (solver/newton.hpp, LineSearch).
// One node in 2D, E(x) = 1/2 m |x - x_hat|^2 + h c f0(|x_0|, eh): the lagged
// friction pseudo-potential of kernels/contact/friction.hpp along the tangent
// e_0, sticking at x_0 = 0 (m |x_hat_0| < h c). On the slip side (|x_0| >= eh)
// its Hessian along a 1D tangent is f1' = 0, so the Newton model is the
// inertia plus a linear friction term and every step overshoots the stick zone
// |x_0| < eh. The minimiser lies inside it, where f1(|x_0|) = m x_hat_0 / (h c).
//   Wolfe: the first step raises E and phi' changes sign on (0, 1); the
//     bisection lands in the stick zone, and the next Hessian (2 h c / eh)
//     gives the minimiser to eps_d in a few iterations.
//   Backtracking: halving lands on either side; it converges only as fast as
//     the dyadic steps happen to close in on a zone 1e-7 wide.
#include <gtest/gtest.h>

#include <Teuchos_DefaultSerialComm.hpp>
#include <cmath>

#include "kernels/contact/friction.hpp"
#include "solver/linear_solver.hpp"
#include "solver/newton.hpp"

using namespace bfemp;

namespace {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "the test term runs its loops on the host");

constexpr double kC = 1e4;     // friction force / h (N): mu lambda
constexpr double kEh = 1e-7;   // eps_v dt (m)

class KinkTerm : public EnergyTerm<2> {
 public:
  std::string name() const override { return "kink"; }
  void add_couplings(NodeGraphBuilder&) const override {}  // node 0's diagonal block only
  double energy(ConstDofView x) const override { return kC * friction_f0(std::fabs(x(0)), kEh); }
  void gradient(ConstDofView x, double scale, DofView grad) const override {
    grad(0) += scale * kC * friction_f1_over_y(std::fabs(x(0)), kEh) * x(0);
  }
  void assemble(ConstDofView x, const Sink<2>& sink) const override {
    gradient(x, sink.scale, sink.grad);
    Eigen::Matrix<double, 1, 1> u;
    u(0) = x(0);
    const double h = sink.scale * kC * friction_f0_hessian<1>(u, kEh)(0, 0);
    const LO col = 0;
    sink.A.sumIntoValues(0, &col, 1, &h, false, false);
  }
  double max_step(ConstDofView, ConstDofView) const override { return INFINITY; }
};

struct Result {
  NewtonStats st;
  double x0 = 0;
  std::string error;
};

Result minimise(LineSearch ls) {
  auto comm = Teuchos::rcp(new Teuchos::SerialComm<int>());
  NewtonParams np;
  np.eps_d = 1e-6;
  np.max_iterations = 200;
  np.line_search = ls;
  NewtonSolver<2> newton(comm, *linear_solver_schema(), np);
  KinkTerm term;
  newton.set_system(1, {&term});
  Kokkos::View<double*, MemSpace> xhat("xhat", 2), mass("mass", 2), target("target", 2), x("x", 2);
  Kokkos::View<int*, MemSpace> pres("pres", 2);
  xhat(0) = 0.3;   // m x_hat_0 = 0.3 < h c = 1: sticks, f1 = 0.3 at the minimiser
  xhat(1) = 0.05;  // the normal DOF: inertia only
  mass(0) = mass(1) = 1.0;
  x(0) = 0.5;  // start sliding, on the slip side
  x(1) = 0.0;
  IncrementalPotential ip;
  ip.x_hat = xhat;
  ip.mass = mass;
  ip.prescribed = pres;
  ip.target = target;
  ip.dt = 0.01;
  ip.h = ip.dt * ip.dt;
  Result r;
  try {
    r.st = newton.minimize(ip, x);
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  r.x0 = x(0);
  return r;
}

TEST(NewtonLineSearch, WolfeLandsInTheStickZoneAndConverges) {
  const Result w = minimise(LineSearch::Wolfe);
  ASSERT_TRUE(w.error.empty()) << w.error;
  // The minimiser: f1(x_0) = 0.3 - x_0 (m = h c = 1) inside (0, eh); with
  // s = x_0 / eh: s^2 - (2 + eh) s + 0.3 = 0. Newton stops at |p| < eps_d dt.
  const double b = 2.0 + kEh;
  const double s = 0.5 * (b - std::sqrt(b * b - 1.2));
  EXPECT_NEAR(w.x0, s * kEh, 1e-3 * kEh);  // quadratic inside the zone: far below eps_d dt = 1e-8
  EXPECT_GE(w.st.wolfe_steps, 1);
  EXPECT_LE(w.st.iterations, 6);
  std::printf("Wolfe: %d Newton iterations, %d Wolfe steps, %d gradient evaluations, x_0 = %.3e m\n",
              w.st.iterations, w.st.wolfe_steps, w.st.wolfe_gradients, w.x0);
}

TEST(NewtonLineSearch, BacktrackingNeedsMoreIterationsOrFails) {
  const Result w = minimise(LineSearch::Wolfe);
  const Result b = minimise(LineSearch::Backtracking);
  EXPECT_EQ(b.st.wolfe_gradients, 0);
  std::printf("backtracking: %s, %d Newton iterations, x_0 = %.3e m\n", b.error.empty() ? "converged" : b.error.c_str(),
              b.st.iterations, b.x0);
  // Measured: 20 iterations against Wolfe's 3 (a failure of the solve counts as worse).
  EXPECT_TRUE(!b.error.empty() || b.st.iterations >= 3 * w.st.iterations)
      << b.st.iterations << " backtracking iterations against " << w.st.iterations;
}

}  // namespace
