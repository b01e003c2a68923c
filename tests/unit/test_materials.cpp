// Constitutive models, 2D and 3D: finite-difference consistency of energy, P, dP/dF; rest
// state, inversion barrier, rotation invariance, small strain, PSD-projected tangent.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "materials/lame.hpp"
#include "materials/linear_elastic.hpp"
#include "materials/material.hpp"
#include "materials/neo_hookean.hpp"

namespace {

using namespace bfemp;

template <class M, int D>
struct Combo { using Model = M; static constexpr int dim = D; };

std::vector<LameParameters> lame_sets() {
  return {lame_from_young(1e6, 0.3), lame_from_young(1e8, 0.2), lame_from_young(1e10, 0.49)};
}

template <int dim>
Mat<dim> random_matrix(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat<dim> A;
  for (int j = 0; j < dim; ++j)
    for (int i = 0; i < dim; ++i) A(i, j) = scale * u(rng);
  return A;
}

template <int dim>
Mat<dim> random_rotation(std::mt19937& rng) {
  Mat<dim> Q = Eigen::HouseholderQR<Mat<dim>>(random_matrix<dim>(rng, 1.0)).householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1.0;
  return Q;
}

// identity, near identity, strongly compressed (J ~ 0.1-0.2), strongly
// sheared (off-diagonal 2), stretched (J ~ 3), random (J > 0.2).
template <int dim>
std::vector<Mat<dim>> test_gradients() {
  std::mt19937 rng(12345);
  const Mat<dim> I = Mat<dim>::Identity();
  Mat<dim> comp = I, stretch = I, shear = I;
  if constexpr (dim == 2) {
    comp.diagonal() << 0.4, 0.35;    // J = 0.14
    stretch.diagonal() << 2.0, 1.5;  // J = 3
  } else {
    comp.diagonal() << 0.5, 0.6, 0.5;      // J = 0.15
    stretch.diagonal() << 1.5, 1.4, 1.43;  // J ~ 3
  }
  shear(0, 1) = 2.0;
  shear(dim - 1, 0) = -0.3;
  std::vector<Mat<dim>> Fs = {I, I + random_matrix<dim>(rng, 0.01), shear,
                              random_rotation<dim>(rng) * comp + random_matrix<dim>(rng, 0.02),
                              stretch * random_rotation<dim>(rng)};
  while (Fs.size() < 10) {
    const Mat<dim> F = I + random_matrix<dim>(rng, 0.6);
    if (F.determinant() > 0.2) Fs.push_back(F);
  }
  return Fs;
}

template <class M>
MaterialParams params_of(const LameParameters& p) {
  MaterialParams mp;
  mp.model = std::is_same<M, NeoHookean>::value ? MaterialModel::NeoHookean
                                                  : MaterialModel::LinearElastic;
  mp.lame = p;
  mp.density = 1000.0;
  return mp;
}

template <class T>
class MaterialTest : public ::testing::Test {};

using Combos = ::testing::Types<Combo<NeoHookean, 2>, Combo<NeoHookean, 3>,
                                Combo<LinearElastic, 2>, Combo<LinearElastic, 3>>;
TYPED_TEST_SUITE(MaterialTest, Combos);

// Central differences; entry m = i + dim * j of F.data() is F(i, j), the
// vec(F) convention of StressDerivative.
TYPED_TEST(MaterialTest, FirstPiolaMatchesFiniteDifferenceOfEnergy) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const double h = 1e-6 * F.cwiseAbs().maxCoeff();
      Mat<dim> P_fd, Fp, Fm;
      for (int m = 0; m < dim * dim; ++m) {
        Fp = Fm = F;
        Fp.data()[m] += h, Fm.data()[m] -= h;
        P_fd.data()[m] = (M::template energy<dim>(Fp, p) - M::template energy<dim>(Fm, p)) / (2 * h);
      }
      const Mat<dim> P = M::template first_piola<dim>(F, p);
      EXPECT_LT((P_fd - P).norm() / (P.norm() + p.mu + p.lambda), 1e-6) << "F =\n" << F;
    }
}

TYPED_TEST(MaterialTest, StressDerivativeMatchesFiniteDifferenceOfStress) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const double h = 1e-6 * F.cwiseAbs().maxCoeff();
      StressDerivative<dim> D_fd;
      Mat<dim> Fp, Fm;
      for (int m = 0; m < dim * dim; ++m) {  // column k + dim * l = m
        Fp = Fm = F;
        Fp.data()[m] += h, Fm.data()[m] -= h;
        const Mat<dim> dP =
            (M::template first_piola<dim>(Fp, p) - M::template first_piola<dim>(Fm, p)) / (2 * h);
        for (int j = 0; j < dim; ++j)
          for (int i = 0; i < dim; ++i) D_fd(i + dim * j, m) = dP(i, j);
      }
      const StressDerivative<dim> D = M::template stress_derivative<dim>(F, p);
      EXPECT_LT((D_fd - D).norm() / (D.norm() + p.mu + p.lambda), 1e-6) << "F =\n" << F;
      // Hessian of psi: exactly symmetric as computed.
      EXPECT_TRUE((D.array() == D.transpose().array()).all());
    }
}

TYPED_TEST(MaterialTest, RestStateIsEnergyAndStressFree) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets()) {
    const Mat<dim> I = Mat<dim>::Identity();
    EXPECT_EQ(M::template energy<dim>(I, p), 0.0);
    EXPECT_LE(M::template first_piola<dim>(I, p).norm(), 1e-14 * (p.mu + p.lambda));
  }
}

// material_* dispatch to the model; the projected tangent is symmetric PSD.
TYPED_TEST(MaterialTest, DispatchAndProjectedStressDerivative) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const MaterialParams mp = params_of<M>(p);
      EXPECT_EQ(material_energy<dim>(mp, F), M::template energy<dim>(F, p));
      EXPECT_TRUE((material_first_piola<dim>(mp, F).array() ==
                   M::template first_piola<dim>(F, p).array()).all());
      const StressDerivative<dim> D = material_stress_derivative_psd<dim>(mp, F);
      EXPECT_TRUE((D.array() == D.transpose().array()).all());
      Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(D);
      EXPECT_GE(es.eigenvalues()(0), -1e-12 * D.norm()) << "F =\n" << F;
    }
}

// Neo-Hookean specific properties, in 2D and 3D.
template <class T>
class MaterialNeoHookeanTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(MaterialNeoHookeanTest, Dims);

TYPED_TEST(MaterialNeoHookeanTest, ProjectedEqualsExactWhereExactIsPsd) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(7);
  for (const LameParameters& p : lame_sets()) {
    const MaterialParams mp = params_of<NeoHookean>(p);
    for (int t = 0; t < 5; ++t) {
      // Slight stretch near identity: exact tangent positive definite (flip modes
      // mu - (mu - lambda log J)/(s_i s_j) need lambda log J <= 2 mu: log J < 0.04).
      const Vec<dim> s = Vec<dim>::LinSpaced(dim, 1.001, 1.001 + 0.001 * (dim - 1));
      const Mat<dim> F = random_rotation<dim>(rng) * s.asDiagonal();
      const StressDerivative<dim> exact = NeoHookean::stress_derivative<dim>(F, p);
      Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(exact);
      ASSERT_GT(es.eigenvalues()(0), 0.0);
      EXPECT_TRUE((material_stress_derivative_psd<dim>(mp, F).array() == exact.array()).all());
    }
    // Strong compression and shear: indefinite exact tangent gets changed.
    Mat<dim> F = 0.3 * Mat<dim>::Identity();
    F(0, 1) = 1.5;
    const StressDerivative<dim> exact = NeoHookean::stress_derivative<dim>(F, p);
    Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(exact);
    ASSERT_LT(es.eigenvalues()(0), 0.0);
    EXPECT_GT((material_stress_derivative_psd<dim>(mp, F) - exact).norm(), 0.0);
  }
}

TYPED_TEST(MaterialNeoHookeanTest, EnergyInfiniteForInvertedOrFlat) {
  constexpr int dim = TypeParam::value;
  constexpr double inf = std::numeric_limits<double>::infinity();
  const LameParameters p = lame_from_young(1e6, 0.3);
  Mat<dim> F = Mat<dim>::Identity();
  F(0, 0) = -0.5;  // J < 0
  EXPECT_EQ(NeoHookean::energy<dim>(F, p), inf);
  EXPECT_TRUE(std::isfinite(LinearElastic::energy<dim>(F, p)));  // no barrier
  F(0, 0) = 0.0;  // J = 0
  EXPECT_EQ(NeoHookean::energy<dim>(F, p), inf);
  EXPECT_EQ(material_energy<dim>(params_of<NeoHookean>(p), F), inf);
  F(0, 0) = 1e-8;  // grows without bound as J -> 0+
  EXPECT_GT(NeoHookean::energy<dim>(F, p), 100.0 * p.mu);
}

TYPED_TEST(MaterialNeoHookeanTest, RotationInvariance) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(99);
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const Mat<dim> R = random_rotation<dim>(rng);
      const double psi = NeoHookean::energy<dim>(F, p);
      EXPECT_NEAR(NeoHookean::energy<dim>(R * F, p), psi, 1e-12 * (p.mu + p.lambda + std::abs(psi)));
      const Mat<dim> P = NeoHookean::first_piola<dim>(F, p);  // frame indifference
      EXPECT_LE((NeoHookean::first_piola<dim>(R * F, p) - R * P).norm(), 1e-11 * (P.norm() + p.mu + p.lambda));
    }
}

TYPED_TEST(MaterialNeoHookeanTest, SmallStrainMatchesHookesLaw) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(3);
  for (const LameParameters& p : lame_sets()) {
    const Mat<dim> G = random_matrix<dim>(rng, 1e-5), F = Mat<dim>::Identity() + G;
    const Mat<dim> eps = 0.5 * (G + G.transpose());  // Hooke's law in components:
    Mat<dim> sigma;
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) sigma(i, j) = 2.0 * p.mu * eps(i, j) + (i == j) * p.lambda * eps.trace();
    const Mat<dim> P_lin = LinearElastic::first_piola<dim>(F, p);
    EXPECT_LE((P_lin - sigma).norm(), 1e-9 * sigma.norm());
    const double w = 0.5 * (sigma.array() * eps.array()).sum();
    EXPECT_NEAR(LinearElastic::energy<dim>(F, p), w, 1e-9 * w);
    // Neo-Hookean linearises to the same law: difference is O(|G|^2), and
    // the tangents agree at the identity.
    EXPECT_LE((NeoHookean::first_piola<dim>(F, p) - P_lin).norm(),
              100.0 * G.squaredNorm() * (p.mu + p.lambda));
    const StressDerivative<dim> D_lin = LinearElastic::stress_derivative<dim>(F, p);
    EXPECT_LE((NeoHookean::stress_derivative<dim>(Mat<dim>::Identity(), p) - D_lin).norm(),
              1e-14 * D_lin.norm());
  }
}

// E = 4e12 at strains 1e-12..1e-6 (the paper's slope box): the neo-Hookean
// energy keeps its relative accuracy against the small-strain energy (the
// direct form mu/2 (|F|^2 - d) - mu log J loses ~mu * 1e-16 absolute, which
// is 1e6 times the strain energy at 1e-12), so a line search can compare
// energies at tiny strains.
TYPED_TEST(MaterialNeoHookeanTest, EnergyAccurateAtTinyStrainsOfStiffMaterials) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(5);
  const LameParameters p = lame_from_young(4e12, 0.2);
  for (double scale : {1e-12, 1e-9, 1e-6}) {
    const Mat<dim> G = random_matrix<dim>(rng, scale), F = Mat<dim>::Identity() + G;
    const double w_lin = LinearElastic::energy<dim>(F, p);
    const double w_nh = NeoHookean::energy<dim>(F, p);
    // Neo-Hookean = linear + O(|G|^3) (E |G|^3 relative to E |G|^2: |G|).
    EXPECT_NEAR(w_nh, w_lin, 1e-6 * w_lin + 10.0 * scale * w_lin) << "strain scale " << scale;
  }
}

TEST(MaterialParams, LameFromYoungAndModelNames) {
  const LameParameters p = lame_from_young(2.0e11, 0.25);
  EXPECT_DOUBLE_EQ(p.mu, 2.0e11 / 2.5);
  EXPECT_DOUBLE_EQ(p.lambda, 2.0e11 * 0.25 / (1.25 * 0.5));
  // E = mu (3 lambda + 2 mu) / (lambda + mu), nu = lambda / (2 (lambda + mu)).
  EXPECT_NEAR(p.mu * (3 * p.lambda + 2 * p.mu) / (p.lambda + p.mu), 2.0e11, 1e-3);
  EXPECT_NEAR(p.lambda / (2 * (p.lambda + p.mu)), 0.25, 1e-15);
  EXPECT_STREQ(material_model_name(MaterialModel::NeoHookean), "neo_hookean");
  EXPECT_STREQ(material_model_name(MaterialModel::LinearElastic), "linear_elastic");
}

}  // namespace
