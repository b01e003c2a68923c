// Constitutive models: finite-difference consistency of energy, P and dP/dF
// for both materials in 2D and 3D, rest state, inversion barrier, rotation
// invariance, small-strain agreement, and the PSD-projected tangent.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "materials/lame.hpp"
#include "materials/linear_elastic.hpp"
#include "materials/material.hpp"
#include "materials/neo_hookean.hpp"

namespace {

using namespace bfemp;

template <class M, int D>
struct Combo {
  using Model = M;
  static constexpr int dim = D;
};

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
  Eigen::HouseholderQR<Mat<dim>> qr(random_matrix<dim>(rng, 1.0));
  Mat<dim> Q = qr.householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1.0;
  return Q;
}

// identity, near identity, strongly compressed (J ~ 0.1-0.2), strongly
// sheared (off-diagonal 2), stretched (J ~ 3), random (J > 0.2).
template <int dim>
std::vector<Mat<dim>> test_gradients() {
  std::mt19937 rng(12345);
  std::vector<Mat<dim>> Fs;
  const Mat<dim> I = Mat<dim>::Identity();
  Fs.push_back(I);
  Fs.push_back(I + random_matrix<dim>(rng, 0.01));
  Mat<dim> comp = I, stretch = I;
  if constexpr (dim == 2) {
    comp.diagonal() << 0.4, 0.35;  // J = 0.14
    stretch.diagonal() << 2.0, 1.5;  // J = 3
  } else {
    comp.diagonal() << 0.5, 0.6, 0.5;  // J = 0.15
    stretch.diagonal() << 1.5, 1.4, 1.43;  // J ~ 3
  }
  Fs.push_back(random_rotation<dim>(rng) * comp + random_matrix<dim>(rng, 0.02));
  Fs.push_back(stretch * random_rotation<dim>(rng));
  Mat<dim> shear = I;
  shear(0, 1) = 2.0;
  shear(dim - 1, 0) = -0.3;
  Fs.push_back(shear);
  while (static_cast<int>(Fs.size()) < 10) {
    const Mat<dim> F = I + random_matrix<dim>(rng, 0.6);
    if (F.determinant() > 0.2) Fs.push_back(F);
  }
  return Fs;
}

template <class T>
class MaterialTest : public ::testing::Test {};

using Combos = ::testing::Types<Combo<NeoHookean, 2>, Combo<NeoHookean, 3>,
                                Combo<LinearElastic, 2>, Combo<LinearElastic, 3>>;
TYPED_TEST_SUITE(MaterialTest, Combos);

TYPED_TEST(MaterialTest, FirstPiolaMatchesFiniteDifferenceOfEnergy) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const double h = 1e-6 * F.cwiseAbs().maxCoeff();
      Mat<dim> P_fd;
      for (int j = 0; j < dim; ++j)
        for (int i = 0; i < dim; ++i) {
          Mat<dim> Fp = F, Fm = F;
          Fp(i, j) += h;
          Fm(i, j) -= h;
          P_fd(i, j) = (M::template energy<dim>(Fp, p) - M::template energy<dim>(Fm, p)) / (2 * h);
        }
      const Mat<dim> P = M::template first_piola<dim>(F, p);
      const double scale = P.norm() + p.mu + p.lambda;
      EXPECT_LT((P_fd - P).norm() / scale, 1e-6) << "F =\n" << F << "\nmu " << p.mu;
    }
}

TYPED_TEST(MaterialTest, StressDerivativeMatchesFiniteDifferenceOfStress) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const double h = 1e-6 * F.cwiseAbs().maxCoeff();
      StressDerivative<dim> D_fd;
      for (int l = 0; l < dim; ++l)
        for (int k = 0; k < dim; ++k) {
          Mat<dim> Fp = F, Fm = F;
          Fp(k, l) += h;
          Fm(k, l) -= h;
          const Mat<dim> dP =
              (M::template first_piola<dim>(Fp, p) - M::template first_piola<dim>(Fm, p)) / (2 * h);
          for (int j = 0; j < dim; ++j)
            for (int i = 0; i < dim; ++i) D_fd(i + dim * j, k + dim * l) = dP(i, j);
        }
      const StressDerivative<dim> D = M::template stress_derivative<dim>(F, p);
      const double scale = D.norm() + p.mu + p.lambda;
      EXPECT_LT((D_fd - D).norm() / scale, 1e-6) << "F =\n" << F;
      // Hyperelastic: dP/dF is the Hessian of psi, hence symmetric.
      EXPECT_LE((D - D.transpose()).norm(), 1e-14 * D.norm());
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

TYPED_TEST(MaterialTest, DispatchMatchesModel) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  MaterialParams mp;
  mp.model = std::is_same<M, NeoHookean>::value ? MaterialModel::NeoHookean
                                                  : MaterialModel::LinearElastic;
  mp.lame = lame_from_young(1e7, 0.35);
  mp.density = 1000.0;
  for (const Mat<dim>& F : test_gradients<dim>()) {
    EXPECT_EQ(material_energy<dim>(mp, F), M::template energy<dim>(F, mp.lame));
    EXPECT_TRUE((material_first_piola<dim>(mp, F).array() ==
                 M::template first_piola<dim>(F, mp.lame).array()).all());
  }
}

TYPED_TEST(MaterialTest, ProjectedStressDerivativeIsPsd) {
  using M = typename TypeParam::Model;
  constexpr int dim = TypeParam::dim;
  MaterialParams mp;
  mp.model = std::is_same<M, NeoHookean>::value ? MaterialModel::NeoHookean
                                                  : MaterialModel::LinearElastic;
  for (const LameParameters& p : lame_sets()) {
    mp.lame = p;
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const StressDerivative<dim> D = material_stress_derivative_psd<dim>(mp, F);
      EXPECT_TRUE((D.array() == D.transpose().array()).all());
      Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(D);
      EXPECT_GE(es.eigenvalues()(0), -1e-12 * D.norm()) << "F =\n" << F;
    }
  }
}

template <int dim>
void check_psd_equals_exact_where_exact_is_psd() {
  std::mt19937 rng(7);
  MaterialParams mp;
  mp.model = MaterialModel::NeoHookean;
  for (const LameParameters& p : lame_sets()) {
    mp.lame = p;
    for (int t = 0; t < 5; ++t) {
      // Slight stretch near identity: every eigenvalue of the exact tangent
      // is positive there.
      Mat<dim> S = Mat<dim>::Identity();
      for (int i = 0; i < dim; ++i) S(i, i) = 1.01 + 0.01 * i;
      const Mat<dim> F = random_rotation<dim>(rng) * S;
      const StressDerivative<dim> exact = NeoHookean::stress_derivative<dim>(F, p);
      Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(0.5 * (exact + exact.transpose()));
      ASSERT_GT(es.eigenvalues()(0), 0.0);
      const StressDerivative<dim> psd = material_stress_derivative_psd<dim>(mp, F);
      EXPECT_TRUE((psd.array() == exact.array()).all());
    }
    // Strong compression: the exact tangent is indefinite and gets changed.
    Mat<dim> F = 0.3 * Mat<dim>::Identity();
    F(0, 1) = 1.5;
    const StressDerivative<dim> exact = NeoHookean::stress_derivative<dim>(F, p);
    Eigen::SelfAdjointEigenSolver<StressDerivative<dim>> es(exact);
    if (es.eigenvalues()(0) < 0.0) {
      const StressDerivative<dim> psd = material_stress_derivative_psd<dim>(mp, F);
      EXPECT_GT((psd - exact).norm(), 0.0);
    }
  }
}

TEST(MaterialPsd, ProjectedEqualsExactWhereExactIsPsd2D) { check_psd_equals_exact_where_exact_is_psd<2>(); }
TEST(MaterialPsd, ProjectedEqualsExactWhereExactIsPsd3D) { check_psd_equals_exact_where_exact_is_psd<3>(); }

template <int dim>
void check_inversion_barrier() {
  const LameParameters p = lame_from_young(1e6, 0.3);
  Mat<dim> F = Mat<dim>::Identity();
  F(0, 0) = -0.5;  // J < 0
  EXPECT_EQ(NeoHookean::energy<dim>(F, p), std::numeric_limits<double>::infinity());
  F(0, 0) = 0.0;  // J = 0
  EXPECT_EQ(NeoHookean::energy<dim>(F, p), std::numeric_limits<double>::infinity());
  MaterialParams mp{MaterialModel::NeoHookean, p, 1.0};
  EXPECT_EQ(material_energy<dim>(mp, F), std::numeric_limits<double>::infinity());
  // Linear elasticity has no barrier: finite for inverted F.
  F(0, 0) = -0.5;
  EXPECT_TRUE(std::isfinite(LinearElastic::energy<dim>(F, p)));
  // Energy grows without bound as J -> 0+.
  F(0, 0) = 1e-8;
  EXPECT_GT(NeoHookean::energy<dim>(F, p), 100.0 * p.mu);
}

TEST(MaterialBarrier, NeoHookeanEnergyInfiniteForInverted2D) { check_inversion_barrier<2>(); }
TEST(MaterialBarrier, NeoHookeanEnergyInfiniteForInverted3D) { check_inversion_barrier<3>(); }

template <int dim>
void check_rotation_invariance() {
  std::mt19937 rng(99);
  for (const LameParameters& p : lame_sets())
    for (const Mat<dim>& F : test_gradients<dim>()) {
      const Mat<dim> R = random_rotation<dim>(rng);
      const double psi = NeoHookean::energy<dim>(F, p);
      const double psi_rot = NeoHookean::energy<dim>(R * F, p);
      EXPECT_NEAR(psi_rot, psi, 1e-12 * (p.mu + p.lambda) + 1e-12 * std::abs(psi));
      // Frame indifference of the stress: P(RF) = R P(F).
      const Mat<dim> P = NeoHookean::first_piola<dim>(F, p);
      const Mat<dim> P_rot = NeoHookean::first_piola<dim>(R * F, p);
      EXPECT_LE((P_rot - R * P).norm(), 1e-11 * (P.norm() + p.mu + p.lambda));
    }
}

TEST(MaterialInvariance, NeoHookeanRotationInvariant2D) { check_rotation_invariance<2>(); }
TEST(MaterialInvariance, NeoHookeanRotationInvariant3D) { check_rotation_invariance<3>(); }

template <int dim>
void check_small_strain() {
  std::mt19937 rng(3);
  for (const LameParameters& p : lame_sets()) {
    const double eps_size = 1e-5;
    const Mat<dim> G = random_matrix<dim>(rng, eps_size);
    const Mat<dim> F = Mat<dim>::Identity() + G;
    // Independent component form of Hooke's law.
    const Mat<dim> eps = 0.5 * (G + G.transpose());
    Mat<dim> sigma;
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) {
        double s = 2.0 * p.mu * eps(i, j);
        if (i == j)
          for (int k = 0; k < dim; ++k) s += p.lambda * eps(k, k);
        sigma(i, j) = s;
      }
    const Mat<dim> P_lin = LinearElastic::first_piola<dim>(F, p);
    EXPECT_LE((P_lin - sigma).norm(), 1e-9 * sigma.norm());
    EXPECT_NEAR(LinearElastic::energy<dim>(F, p), 0.5 * (sigma.array() * eps.array()).sum(),
                1e-9 * 0.5 * (sigma.array() * eps.array()).sum());
    // Neo-Hookean linearises to the same law: difference is O(|G|^2).
    const Mat<dim> P_nh = NeoHookean::first_piola<dim>(F, p);
    EXPECT_LE((P_nh - P_lin).norm(), 100.0 * G.squaredNorm() * (p.mu + p.lambda));
    // ... and the tangents agree at the identity.
    const StressDerivative<dim> D_nh = NeoHookean::stress_derivative<dim>(Mat<dim>::Identity(), p);
    const StressDerivative<dim> D_lin = LinearElastic::stress_derivative<dim>(F, p);
    EXPECT_LE((D_nh - D_lin).norm(), 1e-14 * D_lin.norm());
  }
}

TEST(MaterialSmallStrain, LinearElasticIsHookeAndMatchesNeoHookean2D) { check_small_strain<2>(); }
TEST(MaterialSmallStrain, LinearElasticIsHookeAndMatchesNeoHookean3D) { check_small_strain<3>(); }

TEST(MaterialLame, FromYoung) {
  const LameParameters p = lame_from_young(2.0e11, 0.25);
  EXPECT_DOUBLE_EQ(p.mu, 2.0e11 / 2.5);
  EXPECT_DOUBLE_EQ(p.lambda, 2.0e11 * 0.25 / (1.25 * 0.5));
  // E = mu (3 lambda + 2 mu) / (lambda + mu), nu = lambda / (2 (lambda + mu)).
  EXPECT_NEAR(p.mu * (3 * p.lambda + 2 * p.mu) / (p.lambda + p.mu), 2.0e11, 1e-3);
  EXPECT_NEAR(p.lambda / (2 * (p.lambda + p.mu)), 0.25, 1e-15);
}

TEST(MaterialModelName, Names) {
  EXPECT_STREQ(material_model_name(MaterialModel::NeoHookean), "neo_hookean");
  EXPECT_STREQ(material_model_name(MaterialModel::LinearElastic), "linear_elastic");
}

}  // namespace
