// project_pair_hessian (kernels/contact/pair_projection.hpp) against the full
// n x n eigensolver (project_psd): the same projected barrier Hessian to
// 1e-10 relative, for every closest-feature case of point-point, point-edge
// (2D, 3D) and point-triangle stencils (each case counted among the pairs
// compared), at distances across (0, dhat), with
// positive and negative pair weights (compensation pairs) and with keep > 0;
// and a definite input left bitwise unchanged, as project_psd leaves it.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "kernels/contact/contact_pair.hpp"
#include "kernels/contact/pair_projection.hpp"
#include "materials/psd_projection.hpp"

namespace {

using namespace bfemp;

template <int dim>
Vec<dim> random_vec(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec<dim> v;
  for (int c = 0; c < dim; ++c) v(c) = scale * u(rng);
  return v;
}

struct Tally {
  int projected = 0, unchanged = 0;
  int edge_case[3] = {0, 0, 0};                 // PointEdgeCase of the pairs compared
  int triangle_case[7] = {0, 0, 0, 0, 0, 0, 0};  // PointTriangleCase of the pairs compared
};

// One pair: primitive v[0..nv), point p placed at a distance below dhat.
// noise: false: |fast - ref| <= 1e-10 |H|. true (near-degenerate stencils):
// H itself then carries rounding errors far above 1e-10 |H| (a sliver's G^-1
// is huge and its terms cancel), visible as its asymmetry |H - H^T|; the two
// projections, which both see H only up to that error, must agree to
// 1e-10 |H| + |H - H^T|.
template <int dim, int nv>
void check_pair(const Vec<dim>& p, const Vec<dim>* v, double dhat, double w, double keep, Tally& t,
                bool noise = false) {
  constexpr int L = (1 + nv) * dim;
  const double d2 = stencil_distance2_value<dim, nv>(p, v);
  ASSERT_LT(d2, dhat * dhat);
  const Distance2<L> s = stencil_distance2<dim, nv>(p, v);
  Eigen::Matrix<double, L, 1> g;
  SquareMat<L> H;
  barrier_of_distance2<L>(s, dhat, 1e7, w, g, H);
  SquareMat<L> ref = H, fast = H;
  project_psd<L>(ref, keep);
  project_pair_hessian<dim, L>(s, fast, keep);
  const double scale = H.norm();
  ASSERT_GT(scale, 0.0);
  const double band = 1e-10 * scale + (noise ? (H - H.transpose()).norm() : 0.0);
  EXPECT_LE((fast - ref).norm(), band) << "d = " << std::sqrt(d2) << " w = " << w << " keep = " << keep;
  EXPECT_TRUE((fast.array() == fast.transpose().array()).all());
  if ((fast.array() == H.array()).all()) ++t.unchanged;
  else ++t.projected;
}

// Places p at distance d from the feature point q (on the primitive) along
// direction n, then checks; the case follows from where q lies.
template <int dim, int nv>
void sweep(std::mt19937& rng, int trials, Tally& t) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double dhat = 1e-2;
  for (int k = 0; k < trials; ++k) {
    Vec<dim> v[nv];
    for (int i = 0; i < nv; ++i) v[i] = random_vec<dim>(rng, 0.05);
    // Feature point: a random convex combination, sometimes outside (beyond
    // a vertex or an edge, so the vertex and edge cases occur too).
    Vec<dim> q = Vec<dim>::Zero();
    double sum = 0, b[nv];
    for (int i = 0; i < nv; ++i) sum += (b[i] = u01(rng) + (k % 3 == 0 ? -0.4 : 0.0));
    for (int i = 0; i < nv; ++i) q += (b[i] / sum) * v[i];
    Vec<dim> n = random_vec<dim>(rng, 1.0);
    n.normalize();
    const double d = dhat * std::pow(10.0, -3.0 * u01(rng));  // 1e-5 .. 1e-2
    Vec<dim> p = q + 0.999 * d * n;
    if (!(stencil_distance2_value<dim, nv>(p, v) < dhat * dhat)) continue;
    const double w = (k % 5 == 4) ? -0.5 : 0.3 + u01(rng);  // compensation pairs carry negative weights
    const double keep = (k % 4 == 3) ? 0.25 : 0.0;
    if constexpr (nv == 2) ++t.edge_case[static_cast<int>(point_edge_case<dim>(p, v[0], v[1]))];
    if constexpr (nv == 3) ++t.triangle_case[static_cast<int>(point_triangle_case(p, v[0], v[1], v[2]))];
    check_pair<dim, nv>(p, v, dhat, w, keep, t);
  }
}

TEST(PairProjection, MatchesFullEigensolver2D) {
  std::mt19937 rng(11);
  Tally t;
  sweep<2, 1>(rng, 300, t);
  sweep<2, 2>(rng, 1000, t);
  for (int c = 0; c < 3; ++c) EXPECT_GT(t.edge_case[c], 0) << "point-edge case " << c << " never compared";
  // A barrier Hessian is never PSD: 2 b'(d2) (c c^T (x) I) < 0 across w.
  EXPECT_EQ(t.unchanged, 0);
  EXPECT_GT(t.projected, 1000);
}

TEST(PairProjection, MatchesFullEigensolver3D) {
  std::mt19937 rng(12);
  Tally t;
  sweep<3, 1>(rng, 300, t);
  sweep<3, 2>(rng, 600, t);
  sweep<3, 3>(rng, 1500, t);
  for (int c = 0; c < 3; ++c) EXPECT_GT(t.edge_case[c], 0) << "point-edge case " << c << " never compared";
  for (int c = 0; c < 7; ++c) EXPECT_GT(t.triangle_case[c], 0) << "point-triangle case " << c << " never compared";
  EXPECT_EQ(t.unchanged, 0);
  EXPECT_GT(t.projected, 2000);
}

// A positive definite matrix on the pair's range, grad grad^T + (c c^T (x) I)
// + sum_k (dc_k (x) w)(dc_k (x) w)^T, comes back bitwise.
TEST(PairProjection, PsdInputIsBitwiseUnchanged) {
  const Vec<3> tri[3] = {Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 1, 0)};
  const Distance2<12> s = stencil_distance2<3, 3>(Vec<3>(0.2, 0.3, 0.004), tri);
  ASSERT_EQ(s.nb, 2);
  SquareMat<12> H = 3.0 * s.grad * s.grad.transpose();
  const Vec<3> w = 0.5 * s.grad.head<3>();
  for (int k = 0; k < 2; ++k) {
    Eigen::Matrix<double, 12, 1> col;
    for (int i = 0; i < 4; ++i) col.segment<3>(3 * i) = s.dc[k][i] * w;
    H += col * col.transpose();
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) H.block<3, 3>(3 * i, 3 * j) += s.c[i] * s.c[j] * Mat<3>::Identity();
  const SquareMat<12> before = H;
  project_pair_hessian<3, 12>(s, H);
  EXPECT_TRUE((H.array() == before.array()).all());
}

// Near-degenerate stencils: particles at 1e-14 .. 9e-3 from an edge, over
// its middle and near an endpoint (band 1e-10 |H|), and over sliver
// triangles (height 1e-6, and 1e-9 which the distance treats as collinear),
// where N's columns are nearly parallel and G^-1 is huge: there H's own
// rounding error (6e-6 |H| on the 1e-6 sliver) is the band. Measured on the
// 1e-6 sliver: the range projection differs from the full one by 1.3e-7 |H|
// and from a long-double projection of the same H by the same, the full
// eigensolver from the latter by 2e-15 |H|; H's asymmetry is 6e-6 |H|.
TEST(PairProjection, NearDegenerateStencils) {
  Tally t;
  const double dhat = 1e-2;
  for (double d : {1e-14, 1e-9, 1e-7, 1e-5, 1e-3, 9e-3}) {
    const Vec<2> e[2] = {Vec<2>(0, 0), Vec<2>(1, 0)};
    check_pair<2, 2>(Vec<2>(0.5, d), e, dhat, 1.0, 0.0, t);
    check_pair<2, 2>(Vec<2>(1e-6, d), e, dhat, 1.0, 0.0, t);
    for (double hgt : {1e-6, 1e-9}) {
      const Vec<3> tri[3] = {Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0.5, hgt, 0)};
      check_pair<3, 3>(Vec<3>(0.5, 0.25 * hgt, d), tri, dhat, 1.0, 0.0, t, true);
    }
    const Vec<3> e3[2] = {Vec<3>(0, 0, 0), Vec<3>(0, 0, 1)};
    check_pair<3, 2>(Vec<3>(d, 0, 0.5), e3, dhat, -1.0, 0.5, t);
  }
  EXPECT_GT(t.projected, 0);
}

}  // namespace
