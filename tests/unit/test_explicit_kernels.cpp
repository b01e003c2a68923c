// Kernels of the explicit multimaterial MPM (paper 001): uGIMP and quadratic
// B-spline weights (partition of unity, gradient sum zero, derivative against
// finite differences, 2D and 3D); the Eq. 18 hyperelastic stress against a
// finite-difference derivative of its energy; the contact laws (frictionless,
// Coulomb stick and slip branches, stick, no tension; the pair's momentum is
// unchanged; reduced mass); the LR normal on synthetic clouds (planes at
// several angles, the Fig. 3C corner, a class of 1-2 points) and R_p of
// Eq. 25 for sheared and compressed F.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <type_traits>
#include <vector>

#include "common/grid_fixtures.hpp"
#include "kernels/explicit/contact_law.hpp"
#include "kernels/explicit/logistic_regression.hpp"
#include "kernels/explicit/shape_functions.hpp"
#include "materials/hyperelastic_kg.hpp"

namespace {

using namespace bfemp;
using namespace bfemp::xmpm;

template <class T>
class ExplicitShapes : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(ExplicitShapes, Dims);

// Global nodal function of node n at x (sum over the stencil entries naming n).
template <int dim, class Shape>
double nodal(const GridSpec<dim>& g, LO n, const Vec<dim>& x, double l) {
  const auto st = Shape::template stencil<dim>(g, x, l);
  double w = 0;
  for (int k = 0; k < st.size; ++k)
    if (st.node(g, k) == n) w += st.weight(k);
  return w;
}

template <int dim, class Shape>
void check_shape(double l) {
  const GridSpec<dim> g = fixtures::small_grid<dim>();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int tested = 0;
  for (int t = 0; t < 400; ++t) {
    Vec<dim> x;
    for (int d = 0; d < dim; ++d) x(d) = g.origin[d] + g.dx * (1.0 + 6.0 * u(rng));
    if (t < 30)  // on nodes, cell centres, and the uGIMP breakpoints l, h - l
      for (int d = 0; d < dim; ++d) x(d) = g.origin[d] + g.dx * 3 + (t % 5) * (t % 2 ? l : 0.5 * g.dx);
    ASSERT_TRUE(Shape::template contains<dim>(g, x, l));
    const auto st = Shape::template stencil<dim>(g, x, l);
    double sum = 0;
    Vec<dim> gsum = Vec<dim>::Zero(), lin = Vec<dim>::Zero();
    for (int k = 0; k < st.size; ++k) {
      const double w = st.weight(k);
      EXPECT_GE(w, 0.0);
      sum += w;
      gsum += st.gradient(k);
      lin += w * g.node_position(st.node(g, k));
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_NEAR(gsum.norm(), 0.0, 1e-11);
    EXPECT_NEAR((lin - x).norm(), 0.0, 1e-13);  // linear reproduction
    // gradient against central differences of the global nodal functions
    const double h = 1e-7;
    for (int k = 0; k < st.size; ++k) {
      const LO n = st.node(g, k);
      const Vec<dim> G = st.gradient(k);
      for (int d = 0; d < dim; ++d) {
        Vec<dim> xp = x, xm = x;
        xp(d) += h;
        xm(d) -= h;
        const double fd = (nodal<dim, Shape>(g, n, xp, l) - nodal<dim, Shape>(g, n, xm, l)) / (2 * h);
        EXPECT_NEAR(G(d), fd, 2e-5 / g.dx) << "node " << n << " axis " << d;
      }
    }
    ++tested;
  }
  EXPECT_EQ(tested, 400);
}

TYPED_TEST(ExplicitShapes, UGimpPartitionOfUnityAndGradients) {
  constexpr int dim = TypeParam::value;
  check_shape<dim, UGimp>(0.025);   // 4 (2D) / 8 (3D) particles per cell: l = dx / 4
  check_shape<dim, UGimp>(0.05);    // 1 particle per cell: l = dx / 2
  check_shape<dim, UGimp>(0.0166);  // 9 per cell
}

TYPED_TEST(ExplicitShapes, QuadraticBSplinePartitionOfUnityAndGradients) {
  check_shape<TypeParam::value, QuadraticBSpline>(0.025);
}

TEST(ExplicitShapes, UGimpClosedFormValues) {
  // h = 1, l = 1/4: S(0) = 1 - l/(2h) = 7/8, S(h) = l / (4h)... at |r| = h:
  // (h + l - h)^2 / (4 h l) = l / (4 h) = 1/16; S(1/2) = 1/2; zero at h + l.
  double w, dw;
  UGimp::weight_1d(0.0, 1.0, 0.25, w, dw);
  EXPECT_DOUBLE_EQ(w, 0.875);
  EXPECT_DOUBLE_EQ(dw, 0.0);
  UGimp::weight_1d(1.0, 1.0, 0.25, w, dw);
  EXPECT_DOUBLE_EQ(w, 1.0 / 16);
  UGimp::weight_1d(0.5, 1.0, 0.25, w, dw);
  EXPECT_DOUBLE_EQ(w, 0.5);
  EXPECT_DOUBLE_EQ(dw, -1.0);
  UGimp::weight_1d(1.25, 1.0, 0.25, w, dw);
  EXPECT_DOUBLE_EQ(w, 0.0);
}

// ---- Eq. 18 ----

template <int dim>
void check_kg_stress() {
  const HyperelasticKG m{2450e6, 940e6};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (int t = 0; t < 20; ++t) {
    Mat<dim> F = Mat<dim>::Identity();
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) F(i, j) += u(rng);
    ASSERT_GT(F.determinant(), 0.3);
    const Mat<dim> P = m.first_piola<dim>(F);
    const double h = 1e-6;
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) {
        Mat<dim> Fp = F, Fm = F;
        Fp(i, j) += h;
        Fm(i, j) -= h;
        const double fd = (m.energy<dim>(Fp) - m.energy<dim>(Fm)) / (2 * h);
        EXPECT_NEAR(P(i, j), fd, 1e-6 * P.norm() + 1e-3) << i << j;
      }
    const Mat<dim> sig = m.cauchy<dim>(F);
    EXPECT_LT((sig - P * F.transpose() / F.determinant()).norm(), 1e-9 * sig.norm());
    EXPECT_LT((sig - sig.transpose()).norm(), 1e-9 * sig.norm());
  }
  EXPECT_NEAR(m.energy<dim>(Mat<dim>::Identity()), 0.0, 1e-6);
  EXPECT_LT(m.cauchy<dim>(Mat<dim>::Identity()).norm(), 1e-6);
  // small strain: sigma = K tr(eps) I + 2 G dev3(eps)
  Mat<dim> F = Mat<dim>::Identity();
  const double e = 1e-7;
  F(dim - 1, dim - 1) += e;
  const Mat<dim> sig = m.cauchy<dim>(F);
  EXPECT_NEAR(sig(dim - 1, dim - 1), (m.K + 4.0 / 3.0 * m.G) * e, 1e-5 * m.K * e);
  EXPECT_NEAR(sig(0, 0), (m.K - 2.0 / 3.0 * m.G) * e, 1e-5 * m.K * e);
}

TEST(ExplicitMaterial, HyperelasticKGStressIsEnergyDerivative2D) { check_kg_stress<2>(); }
TEST(ExplicitMaterial, HyperelasticKGStressIsEnergyDerivative3D) { check_kg_stress<3>(); }

// ---- contact laws ----

TEST(ExplicitContactLaw, FrictionlessCoulombStickAndNoTension) {
  using V = Vec<2>;
  const double ma = 2.0, mb = 3.0;
  const V n(0.0, 1.0);  // alpha below, beta above
  const double mred = ma * mb / (ma + mb);
  // approaching: alpha moves up at 1, beta down at 1, with tangential slip 0.5
  const V va(0.5, 1.0), vb(0.0, -1.0);
  const V pa = ma * va, pb = mb * vb;
  const V dp0 = center_of_mass_change<2>(ma, pa, mb, pb);
  EXPECT_NEAR((dp0 - mred * (vb - va)).norm(), 0.0, 1e-15);  // Eq. 8 with the reduced mass
  bool act;
  // frictionless: only the normal part; normal velocities equal afterwards
  V dp = contact_momentum_change<2>({ContactLaw::Frictionless, 0}, ma, pa, mb, pb, n, act);
  EXPECT_TRUE(act);
  EXPECT_NEAR(dp(0), 0.0, 1e-15);
  EXPECT_NEAR((pb - dp)(1) / mb - (pa + dp)(1) / ma, 0.0, 1e-14);
  // stick (and Coulomb with a large mu): both move with v_cm
  const V vcm = (pa + pb) / (ma + mb);
  for (const LawParams law : {LawParams{ContactLaw::Stick, 0}, LawParams{ContactLaw::Coulomb, 10.0}}) {
    dp = contact_momentum_change<2>(law, ma, pa, mb, pb, n, act);
    EXPECT_TRUE(act);
    EXPECT_NEAR(((pa + dp) / ma - vcm).norm(), 0.0, 1e-14);
    EXPECT_NEAR(((pb - dp) / mb - vcm).norm(), 0.0, 1e-14);
  }
  // Coulomb slip branch: tangential impulse = mu |normal impulse|, same sense as dp0_t
  const double mu = 0.1;
  dp = contact_momentum_change<2>({ContactLaw::Coulomb, mu}, ma, pa, mb, pb, n, act);
  EXPECT_TRUE(act);
  EXPECT_NEAR(dp(1), dp0(1), 1e-15);
  EXPECT_NEAR(dp(0), mu * std::fabs(dp0(1)) * (dp0(0) > 0 ? 1 : -1), 1e-15);
  EXPECT_LT(std::fabs(dp(0)), std::fabs(dp0(0)));  // still slipping
  // Coulomb stick branch: |dp0_t| <= mu |dp0_n|
  const double mu_stick = std::fabs(dp0(0) / dp0(1)) * 1.0001;
  dp = contact_momentum_change<2>({ContactLaw::Coulomb, mu_stick}, ma, pa, mb, pb, n, act);
  EXPECT_NEAR((dp - dp0).norm(), 0.0, 1e-15);
  // no tension: separating materials are left alone (except by stick)
  const V qa = ma * V(0.2, -1.0), qb = mb * V(0.0, 1.0);
  for (const ContactLaw l : {ContactLaw::Frictionless, ContactLaw::Coulomb}) {
    dp = contact_momentum_change<2>({l, 0.3}, ma, qa, mb, qb, n, act);
    EXPECT_FALSE(act);
    EXPECT_EQ(dp.norm(), 0.0);
  }
  dp = contact_momentum_change<2>({ContactLaw::Stick, 0}, ma, qa, mb, qb, n, act);
  EXPECT_TRUE(act);
  // 3D, oblique normal: pair momentum conserved by construction (beta gets -dp), stick/slip
  const Vec<3> n3 = Vec<3>(1, 2, 2) / 3.0;
  const Vec<3> pa3(1, 2, 3), pb3(-4, -2, 0.5);
  const Vec<3> d3 = contact_momentum_change<3>({ContactLaw::Coulomb, 0.2}, 1.5, pa3, 0.7, pb3, n3, act);
  EXPECT_TRUE(act);
  const Vec<3> d30 = center_of_mass_change<3>(1.5, pa3, 0.7, pb3);
  EXPECT_NEAR(d3.dot(n3), d30.dot(n3), 1e-14);
  EXPECT_NEAR((d3 - d3.dot(n3) * n3).norm(), 0.2 * std::fabs(d30.dot(n3)), 1e-14);
}

// ---- LR ----

struct Cloud2 {
  std::vector<Vec<2>> x;
  std::vector<double> c;
  template <class G>
  void operator()(G&& g) const {
    for (std::size_t i = 0; i < x.size(); ++i) g(x[i], c[i]);
  }
};

// 4 points per cell (2 x 2) in the 2 x 2 cells around a node at the origin,
// dx = 1; class by side of the line through `offset` with normal (cos t, sin t).
Cloud2 plane_cloud(double theta, double offset, double dx) {
  Cloud2 cl;
  const Vec<2> n(std::cos(theta), std::sin(theta));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const Vec<2> x((i - 1.5) * dx / 2, (j - 1.5) * dx / 2);
      const double s = x.dot(n) - offset * dx;
      if (std::fabs(s) < 1e-12) continue;
      cl.x.push_back(x);
      cl.c.push_back(s < 0 ? -1.0 : 1.0);
    }
  return cl;
}

TEST(ExplicitLR, PlaneAtSeveralAnglesGivesItsNormal) {
  // Point clouds that a plane separates, at several angles and offsets; each
  // material a half-space of a dense lattice, so the separating line is unique
  // up to the lattice spacing only for grid-aligned cuts: test on an oriented
  // lattice (points rotated with the plane) so that the exact answer is n.
  for (double dx : {1.0, 0.005}) {
    for (double deg : {0.0, 10.0, 30.0, 45.0, 60.0, 77.0, 90.0, 135.0, 200.0, 290.0}) {
      const double t = deg * M_PI / 180.0;
      const Vec<2> n(std::cos(t), std::sin(t)), tg(-std::sin(t), std::cos(t));
      Cloud2 cl;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {  // lattice aligned with the plane, offset by half a spacing
          const double a = (i - 1.5) * dx / 2, b = (j - 1.5) * dx / 2 + 0.1 * dx;
          cl.x.push_back(a * tg + b * n);
          cl.c.push_back(b < 0 ? -1.0 : 1.0);
        }
      const LRResult<2> r = lr_fit<2>(cl, dx);
      const double ang = std::acos(std::min(1.0, r.normal.dot(n)));
      EXPECT_LT(ang, 0.0044) << deg << " deg, dx " << dx << ": " << r.iterations << " iterations";
      EXPECT_LE(r.iterations, 15);
    }
  }
}

TEST(ExplicitLR, GridAlignedCloudsAtSeveralAngles) {
  // The MPM situation: particles on the grid lattice (4 per cell around the
  // node), classes split by a line at an angle. The fitted normal must be
  // within 0.0044 rad of the line's normal whenever the split is the same as
  // the line's (a symmetric cut: the line through the node at 0, 45, 90 deg).
  for (double deg : {0.0, 45.0, 90.0, 135.0, 180.0, 270.0}) {
    const double t = deg * M_PI / 180.0;
    const Cloud2 cl = plane_cloud(t, 0.0, 1.0);
    const LRResult<2> r = lr_fit<2>(cl, 1.0);
    const double ang = std::acos(std::min(1.0, r.normal.dot(Vec<2>(std::cos(t), std::sin(t)))));
    EXPECT_LT(ang, 0.0044) << deg << " deg";
  }
}

TEST(ExplicitLR, FirstIterateIsLinearRegression) {
  // phi^(0) = 0: phi^(1) = (X^T X / 4 + Lambda)^-1 X^T c / 2 (the linear least-squares plane).
  const Cloud2 cl = plane_cloud(0.3, 0.1, 1.0);
  LRSettings one;
  one.max_iterations = 1;
  const LRResult<2> r = lr_fit<2>(cl, 1.0, one);
  double A[3][3] = {}, b[3] = {}, y[3];
  for (std::size_t i = 0; i < cl.x.size(); ++i) {
    const double xh[3] = {cl.x[i](0), cl.x[i](1), 1.0};
    for (int k = 0; k < 3; ++k) {
      b[k] += 0.5 * cl.c[i] * xh[k];
      for (int l = 0; l < 3; ++l) A[k][l] += 0.25 * xh[k] * xh[l];
    }
  }
  A[0][0] += 1e-7;
  A[1][1] += 1e-7;
  small_solve<3>(A, b, y);
  const Vec<2> n = Vec<2>(y[0], y[1]).normalized();
  EXPECT_NEAR(r.normal.dot(n), 1.0, 1e-14);
  EXPECT_EQ(r.iterations, 1);
}

TEST(ExplicitLR, Fig3CCornerGivesTheHorizontalPlane) {
  // Fig. 3C: node at the origin (dx = 1), beta a full edge above (both upper
  // cells), alpha only in the lower-left cell (a corner of alpha at the node).
  Cloud2 cl;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 2; ++j) {
      cl.x.push_back(Vec<2>((i - 1.5) / 2, 0.25 + 0.5 * j));
      cl.c.push_back(1.0);
    }
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      cl.x.push_back(Vec<2>(-0.75 + 0.5 * i, -0.75 + 0.5 * j));
      cl.c.push_back(-1.0);
    }
  const LRResult<2> r = lr_fit<2>(cl, 1.0);
  const double ang = std::acos(std::min(1.0, r.normal.dot(Vec<2>(0, 1))));
  LRSettings one;
  one.max_iterations = 1;
  const LRResult<2> lin = lr_fit<2>(cl, 1.0, one);
  const double ang_lin = std::acos(std::min(1.0, lin.normal.dot(Vec<2>(0, 1))));
  // The issue gives no band here. Measured: linear regression (phi^(1)) 0.136
  // rad, the appendix's LR 0.0266 rad after its stop, 0.0256 rad in the limit
  // (1000 iterations); AG by Eq. 13 tilts by about 18 degrees (0.31 rad,
  // paper). The LR plane is horizontal to 1.5 degrees, not exactly: the cloud
  // is not symmetric.
  EXPECT_GT(ang_lin, 0.1);
  EXPECT_LT(ang, 0.03) << "LR normal (" << r.normal.transpose() << "), " << r.iterations << " iterations";
  EXPECT_LT(ang, 0.25 * ang_lin);
}
TEST(ExplicitLR, ClassWithOneOrTwoPointsStopsWithAUsableNormal) {
  for (int nb : {1, 2}) {
    Cloud2 cl;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 2; ++j) {
        cl.x.push_back(Vec<2>((i - 1.5) / 2, -0.25 - 0.5 * j));
        cl.c.push_back(-1.0);
      }
    for (int k = 0; k < nb; ++k) {
      cl.x.push_back(Vec<2>(-0.25 + 0.5 * k, 0.25));
      cl.c.push_back(1.0);
    }
    const LRResult<2> r = lr_fit<2>(cl, 1.0);
    EXPECT_LE(r.iterations, 15);
    EXPECT_NEAR(r.normal.norm(), 1.0, 1e-12);
    EXPECT_GT(r.normal(1), 0.9) << nb << " beta points: normal " << r.normal.transpose();
  }
}

TEST(ExplicitLR, PlaneIn3D) {
  for (double deg : {0.0, 30.0, 90.0}) {
    const double t = deg * M_PI / 180;
    const Vec<3> n(std::sin(t), 0.0, std::cos(t));
    const Vec<3> t1(std::cos(t), 0.0, -std::sin(t)), t2(0, 1, 0);
    std::vector<Vec<3>> xs;
    std::vector<double> cs;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k) {
          const double c = (k - 1.5) / 2 + 0.1;
          xs.push_back(((i - 1.5) / 2) * t1 + ((j - 1.5) / 2) * t2 + c * n);
          cs.push_back(c < 0 ? -1 : 1);
        }
    auto cloud = [&](auto&& g) {
      for (std::size_t i = 0; i < xs.size(); ++i) g(xs[i], cs[i]);
    };
    const LRResult<3> r = lr_fit<3>(cloud, 1.0);
    EXPECT_LT(std::acos(std::min(1.0, r.normal.dot(n))), 0.0044) << deg;
  }
}

TEST(ExplicitLR, EllipsoidRadiusForShearedAndCompressedF) {
  const Vec<2> R0(1.25e-3, 1.25e-3);
  // undeformed: R0 along any direction (a circle)
  EXPECT_NEAR(ellipsoid_radius<2>(Mat<2>::Identity(), R0, Vec<2>(0.6, 0.8)), 1.25e-3, 1e-18);
  // compressed along y by 0.8: R = 0.8 R0 along y, R0 along x
  Mat<2> F = Mat<2>::Identity();
  F(1, 1) = 0.8;
  EXPECT_NEAR(ellipsoid_radius<2>(F, R0, Vec<2>(0, 1)), 0.8 * 1.25e-3, 1e-17);
  EXPECT_NEAR(ellipsoid_radius<2>(F, R0, Vec<2>(1, 0)), 1.25e-3, 1e-17);
  // simple shear F = [[1, g], [0, 1]]: along y, R = R0 / sqrt(1 + g^2)
  Mat<2> S = Mat<2>::Identity();
  S(0, 1) = 0.5;
  EXPECT_NEAR(ellipsoid_radius<2>(S, R0, Vec<2>(0, 1)), 1.25e-3 / std::sqrt(1.25), 1e-17);
  // any F, direction: the point R n lies on the deformed ellipse F {|X / R0| = 1}
  Mat<2> A;
  A << 1.1, 0.3, -0.2, 0.7;
  const Vec<2> R0b(1e-3, 2e-3);
  for (double t = 0; t < 6; t += 0.7) {
    const Vec<2> n(std::cos(t), std::sin(t));
    const double R = ellipsoid_radius<2>(A, R0b, n);
    const Vec<2> X = A.inverse() * (R * n);
    EXPECT_NEAR(std::pow(X(0) / R0b(0), 2) + std::pow(X(1) / R0b(1), 2), 1.0, 1e-12);
  }
  // 3D cube compressed: R = R0 / |n0|
  Mat<3> F3 = Mat<3>::Identity();
  F3(2, 2) = 0.5;
  EXPECT_NEAR(ellipsoid_radius<3>(F3, Vec<3>(1, 1, 1), Vec<3>(0, 0, 1)), 0.5, 1e-15);
}

}  // namespace
