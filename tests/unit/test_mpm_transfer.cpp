// MPM particle-grid transfers (kernels/mpm_transfer.hpp), 2D and 3D, on
// randomly placed particles:
// - G2P of an affine grid motion, v_i = b + A x_i and x~_i = x_i + dt v_i,
//   is exact for quadratic B-splines (sum w = 1, sum w r = 0,
//   sum w r r^T = D = dx^2/4 I): v_p = b + A x_p, x_p <- x_p + dt v_p,
//   F_p <- (I + dt A) F_p, and APIC's C_p = B_p D^-1 = A (paper Table 1,
//   with its x~ terms: they add 1/2 (A D - D A^T) to the symmetric part's
//   1/2 (A D + D A^T)), so a wrong antisymmetric part of B fails here;
//   FLIP adds the change of the grid velocity to v_p, PIC and FLIP leave C.
// - P2G conserves mass, momentum and (APIC) angular momentum: sum_i m_i =
//   sum_p m_p, sum_i m_i v_i = sum_p m_p v_p, and
//   sum_i x_i x (m v)_i = sum_p m_p (x_p x v_p + C_p : D-term), which for
//   APIC is sum_p m_p x_p x v_p + m_p eps : (C_p D)^T (checked in 2D and 3D).
// - P2G at the suite's 2 threads (per-thread copies of the grid, summed after)
//   equals a plain host sum in particle order to round-off.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <type_traits>

#include "common/grid_fixtures.hpp"
#include "kernels/mpm_transfer.hpp"

namespace {

using namespace bfemp;

template <class T>
class MpmTransfer : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(MpmTransfer, Dims);

// n particles inside [origin + 2 dx, origin + 6 dx]^dim, random v, C, F near I.
template <int dim>
Particles<dim> random_particles(const GridSpec<dim>& g, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1), s(-1, 1);
  auto p = allocate_particles<dim>(n);
  for (int q = 0; q < n; ++q) {
    p.mass(q) = 0.5 + u(rng);
    p.volume0(q) = 1e-3;
    for (int i = 0; i < dim; ++i) {
      p.x(q, i) = g.origin[i] + g.dx * (2 + 4 * u(rng));
      p.v(q, i) = s(rng);
      for (int j = 0; j < dim; ++j) {
        p.C(q, i, j) = s(rng);
        p.F(q, i, j) = (i == j ? 1.0 : 0.0) + 0.1 * s(rng);
      }
    }
  }
  return p;
}

template <int dim>
void check_affine_g2p(TransferScheme scheme) {
  const auto g = fixtures::small_grid<dim>();
  auto p = random_particles<dim>(g, 40, 7);
  Kokkos::View<LO*, MemSpace> system_node("sn", g.num_nodes()), grid_node;
  const LO n = activate_grid<dim>(g, p, 0, system_node, grid_node);
  Mat<dim> A;
  Vec<dim> b;
  for (int i = 0; i < dim; ++i) {
    b(i) = 0.3 * (i + 1);
    for (int j = 0; j < dim; ++j) A(i, j) = 0.7 * (i + 1) - 0.4 * j * j + (i == j ? 0.2 : 0.0);
  }
  const double dt = 0.01;
  Kokkos::View<double*, MemSpace> xt("xt", n * dim), vt("vt", n * dim), v0("v0", n * dim);
  for (LO k = 0; k < n; ++k) {
    const Vec<dim> xi = g.node_position(grid_node(k));
    const Vec<dim> vi = b + A * xi;
    for (int c = 0; c < dim; ++c) {
      vt(k * dim + c) = vi(c);
      xt(k * dim + c) = xi(c) + dt * vi(c);
      v0(k * dim + c) = 0.25 * vi(c) - 0.1;  // grid velocity at t^n (FLIP reads it)
    }
  }
  auto before = allocate_particles<dim>(p.size());
  Kokkos::deep_copy(before.x, p.x);
  Kokkos::deep_copy(before.v, p.v);
  Kokkos::deep_copy(before.F, p.F);
  Kokkos::deep_copy(before.C, p.C);
  g2p(g, p, scheme, system_node, xt, vt, v0);
  Kokkos::fence();
  for (std::size_t q = 0; q < p.size(); ++q) {
    Vec<dim> x0;
    Mat<dim> F0;
    for (int i = 0; i < dim; ++i) {
      x0(i) = before.x(q, i);
      for (int j = 0; j < dim; ++j) F0(i, j) = before.F(q, i, j);
    }
    const Vec<dim> vp = b + A * x0;
    const Mat<dim> F1 = (Mat<dim>::Identity() + dt * A) * F0;
    for (int i = 0; i < dim; ++i) {
      EXPECT_NEAR(p.x(q, i), x0(i) + dt * vp(i), 1e-13) << "particle " << q;
      const double v_expected =
          scheme == TransferScheme::FLIP ? before.v(q, i) + (vp(i) - (0.25 * vp(i) - 0.1)) : vp(i);
      EXPECT_NEAR(p.v(q, i), v_expected, 1e-12) << "particle " << q << ", component " << i;
      for (int j = 0; j < dim; ++j) {
        EXPECT_NEAR(p.F(q, i, j), F1(i, j), 1e-12) << "particle " << q;
        const double c_expected = scheme == TransferScheme::APIC ? A(i, j) : before.C(q, i, j);
        EXPECT_NEAR(p.C(q, i, j), c_expected, 1e-10) << "particle " << q << ", C(" << i << "," << j << ")";
      }
    }
  }
}

TYPED_TEST(MpmTransfer, G2PReproducesAnAffineGridMotion) {
  constexpr int dim = TypeParam::value;
  for (const auto s : {TransferScheme::APIC, TransferScheme::PIC, TransferScheme::FLIP}) {
    SCOPED_TRACE(transfer_scheme_name(s));
    check_affine_g2p<dim>(s);
  }
}

// P2G into GridScatter copies, reset and contributed as MpmBodies does.
template <int dim>
void run_p2g(const GridSpec<dim>& g, const Particles<dim>& p, TransferScheme scheme,
             Kokkos::View<const LO*, MemSpace> system_node, LO n, Kokkos::View<double*, MemSpace>& mass,
             Kokkos::View<double*, MemSpace>& mom) {
  mass = Kokkos::View<double*, MemSpace>("m", n);
  mom = Kokkos::View<double*, MemSpace>("mv", n * dim);
  GridScatter ms(mass), vs(mom);
  ms.reset();
  vs.reset();
  p2g(g, p, scheme, system_node, 0, ms, vs);
  Kokkos::Experimental::contribute(mass, ms);
  Kokkos::Experimental::contribute(mom, vs);
  Kokkos::fence();
}

// Angular momentum about the origin, as a vector of 3 (2D: z only).
template <int dim>
Eigen::Vector3d cross3(const Vec<dim>& a, const Vec<dim>& b) {
  Eigen::Vector3d a3 = Eigen::Vector3d::Zero(), b3 = Eigen::Vector3d::Zero();
  for (int i = 0; i < dim; ++i) a3(i) = a(i), b3(i) = b(i);
  return a3.cross(b3);
}

TYPED_TEST(MpmTransfer, P2GConservesMassMomentumAndApicAngularMomentum) {
  constexpr int dim = TypeParam::value;
  const auto g = fixtures::small_grid<dim>();
  const auto p = random_particles<dim>(g, 60, 11);
  Kokkos::View<LO*, MemSpace> system_node("sn", g.num_nodes()), grid_node;
  const LO n = activate_grid<dim>(g, p, 0, system_node, grid_node);
  Kokkos::View<double*, MemSpace> mass, mom;
  run_p2g<dim>(g, p, TransferScheme::APIC, system_node, n, mass, mom);
  const double D = g.dx * g.dx / 4;
  double mp_sum = 0;
  Vec<dim> pp = Vec<dim>::Zero();
  Eigen::Vector3d Lp = Eigen::Vector3d::Zero();
  for (std::size_t q = 0; q < p.size(); ++q) {
    Vec<dim> x, v;
    Mat<dim> C;
    for (int i = 0; i < dim; ++i) {
      x(i) = p.x(q, i);
      v(i) = p.v(q, i);
      for (int j = 0; j < dim; ++j) C(i, j) = p.C(q, i, j);
    }
    mp_sum += p.mass(q);
    pp += p.mass(q) * v;
    Lp += p.mass(q) * cross3<dim>(x, v);
    // sum_i w_i (x_i - x_p) x (C (x_i - x_p)) = eps_abc D C_cb: the affine part's spin.
    Mat<dim> CD = D * C;
    Eigen::Vector3d spin = Eigen::Vector3d::Zero();
    if constexpr (dim == 3) {
      spin << CD(2, 1) - CD(1, 2), CD(0, 2) - CD(2, 0), CD(1, 0) - CD(0, 1);
    } else {
      spin(2) = CD(1, 0) - CD(0, 1);
    }
    Lp += p.mass(q) * spin;
  }
  double mi_sum = 0;
  Vec<dim> pi = Vec<dim>::Zero();
  Eigen::Vector3d Li = Eigen::Vector3d::Zero();
  for (LO k = 0; k < n; ++k) {
    const Vec<dim> xi = g.node_position(grid_node(k));
    Vec<dim> mv;
    for (int c = 0; c < dim; ++c) mv(c) = mom(k * dim + c);
    mi_sum += mass(k);
    pi += mv;
    Li += cross3<dim>(xi, mv);
  }
  EXPECT_NEAR(mi_sum, mp_sum, 1e-12 * mp_sum);
  for (int c = 0; c < dim; ++c) EXPECT_NEAR(pi(c), pp(c), 1e-12 * mp_sum) << "momentum " << c;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(Li(c), Lp(c), 1e-12 * mp_sum) << "angular momentum " << c;
}

TYPED_TEST(MpmTransfer, P2GMatchesAPlainSumInParticleOrder) {
  constexpr int dim = TypeParam::value;
  const auto g = fixtures::small_grid<dim>();
  const auto p = random_particles<dim>(g, 500, 13);
  Kokkos::View<LO*, MemSpace> system_node("sn", g.num_nodes()), grid_node;
  const LO n = activate_grid<dim>(g, p, 0, system_node, grid_node);
  Kokkos::View<double*, MemSpace> m2, v2, m1, v1;
  run_p2g<dim>(g, p, TransferScheme::APIC, system_node, n, m2, v2);
  // The same sums in particle order on the host, from the per-node stencil queries.
  m1 = Kokkos::View<double*, MemSpace>("m1", n);
  v1 = Kokkos::View<double*, MemSpace>("v1", n * dim);
  for (std::size_t q = 0; q < p.size(); ++q) {
    Vec<dim> xp, vp;
    for (int c = 0; c < dim; ++c) xp(c) = p.x(q, c), vp(c) = p.v(q, c);
    const auto st = bspline_stencil(g, xp);
    for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
      const LO k = system_node(node_index(g, st, a));
      const double w = weight(st, a) * p.mass(q);
      const Vec<dim> r = g.node_position(node_index(g, st, a)) - xp;
      m1(k) += w;
      for (int c = 0; c < dim; ++c) {
        double v = vp(c);
        for (int d = 0; d < dim; ++d) v += p.C(q, c, d) * r(d);
        v1(k * dim + c) += w * v;
      }
    }
  }
  for (LO k = 0; k < n; ++k) {
    EXPECT_NEAR(m2(k), m1(k), 1e-14 * (1 + std::abs(m1(k)))) << "node " << k;
    for (int c = 0; c < dim; ++c) EXPECT_NEAR(v2(k * dim + c), v1(k * dim + c), 1e-13 * (1 + std::abs(v1(k * dim + c))));
  }
}

}  // namespace
