// Multimaterial XPIC(m) of paper 001 §3.3 (kernels/explicit/fields.hpp):
// the v*^alpha task of Eqs. 42-44 against the explicit matrix formulas on a
// tiny grid. With dense per-class matrices S (particles x nodes, uGIMP) and
// S^{+alpha} = (m^alpha)^-1 S^T M_p:
//   Eq. 36/37: P V = (I - (I - S S^{+a})^m) V + (I - S S^{+a})^(m-1) S Delta v^a
// must equal m S (v^a - v*^a) with v^a = S^{+a} V + Delta v^a (Eq. 41), for
// m = 1..6, one and two classes; and XPIC(1) = PIC: v* = 0, P V = S v^a (Eq. 38).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "kernels/explicit/fields.hpp"
#include "kernels/explicit/shape_functions.hpp"

namespace {

using namespace bfemp;
using namespace bfemp::xmpm;

struct Tiny {
  GridSpec<2> g;
  XParticles<2> p;
  int M = 0;
  LO nn = 0;
  std::size_t np = 0;
  std::vector<Eigen::MatrixXd> S;  // per class: (particles of the class) x nodes
  std::vector<std::vector<int>> members;
  Kokkos::View<double*, MemSpace> gm;
};

// n_per_class particles per class, random in the inner cells of a 6 x 6 grid.
Tiny make(int M, int n_per_class, unsigned seed) {
  Tiny t;
  t.M = M;
  t.g.dx = 0.1;
  t.g.origin = Vec<2>(0.0, 0.0);
  t.g.n_cells = {6, 6};
  t.nn = t.g.num_nodes();
  t.np = static_cast<std::size_t>(M * n_per_class);
  t.p.x = decltype(t.p.x)("x", t.np);
  t.p.v = decltype(t.p.v)("v", t.np);
  t.p.mass = Kokkos::View<double*, MemSpace>("m", t.np);
  t.p.volume0 = Kokkos::View<double*, MemSpace>("V0", t.np);
  t.p.lp = Kokkos::View<double*, MemSpace>("lp", t.np);
  t.p.cls = Kokkos::View<int*, MemSpace>("cls", t.np);
  t.p.body = Kokkos::View<int*, MemSpace>("body", t.np);
  auto x = Kokkos::create_mirror_view(t.p.x);
  auto v = Kokkos::create_mirror_view(t.p.v);
  auto m = Kokkos::create_mirror_view(t.p.mass);
  auto lp = Kokkos::create_mirror_view(t.p.lp);
  auto c = Kokkos::create_mirror_view(t.p.cls);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t q = 0; q < t.np; ++q) {
    const int a = static_cast<int>(q) / n_per_class;
    // class 0 on the left half (x < 0.32), class 1 on the right (x > 0.28): they overlap at contact nodes
    const double x0 = M == 1 ? 0.2 + 0.2 * u(rng) : (a == 0 ? 0.2 + 0.12 * u(rng) : 0.28 + 0.12 * u(rng));
    x(q, 0) = x0;
    x(q, 1) = 0.2 + 0.2 * u(rng);
    v(q, 0) = u(rng) - 0.5;
    v(q, 1) = u(rng) - 0.5;
    m(q) = 0.5 + u(rng);
    lp(q) = 0.025;
    c(q) = a;
  }
  Kokkos::deep_copy(t.p.x, x);
  Kokkos::deep_copy(t.p.v, v);
  Kokkos::deep_copy(t.p.mass, m);
  Kokkos::deep_copy(t.p.lp, lp);
  Kokkos::deep_copy(t.p.cls, c);
  t.S.assign(M, Eigen::MatrixXd());
  t.members.assign(M, {});
  for (std::size_t q = 0; q < t.np; ++q) t.members[c(q)].push_back(static_cast<int>(q));
  auto hgm = Kokkos::View<double*, Kokkos::HostSpace>("gm", static_cast<std::size_t>(t.nn) * M);
  for (int a = 0; a < M; ++a) {
    t.S[a] = Eigen::MatrixXd::Zero(t.members[a].size(), t.nn);
    for (std::size_t r = 0; r < t.members[a].size(); ++r) {
      const int q = t.members[a][r];
      const auto st = UGimp::stencil<2>(t.g, Vec<2>(x(q, 0), x(q, 1)), lp(q));
      for (int k = 0; k < st.size; ++k) {
        t.S[a](r, st.node(t.g, k)) += st.weight(k);
        hgm(st.node(t.g, k) * M + a) += st.weight(k) * m(q);
      }
    }
  }
  t.gm = Kokkos::View<double*, MemSpace>("gm", hgm.extent(0));
  Kokkos::deep_copy(t.gm, hgm);
  return t;
}

void check(int M, int order, bool with_dv, unsigned seed) {
  Tiny t = make(M, 14, seed);
  const std::size_t ns = static_cast<std::size_t>(t.nn) * M;
  auto hm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), t.p.mass);
  auto hv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), t.p.v);
  auto hgm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), t.gm);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  // per class: V (particles x 2), S^+ (nodes x particles), v0 = S^+ V, Delta v (nonzero only where m > 0)
  std::vector<Eigen::MatrixXd> V(M), Sp(M), dv(M), va(M);
  Kokkos::View<double*, Kokkos::HostSpace> hv1("v1", ns * 2), hdv("dv", ns * 2);
  for (int a = 0; a < M; ++a) {
    const auto& mem = t.members[a];
    V[a].resize(mem.size(), 2);
    Eigen::VectorXd mp(mem.size());
    for (std::size_t r = 0; r < mem.size(); ++r) {
      V[a](r, 0) = hv(mem[r], 0);
      V[a](r, 1) = hv(mem[r], 1);
      mp(r) = hm(mem[r]);
    }
    Sp[a] = Eigen::MatrixXd::Zero(t.nn, mem.size());
    for (LO i = 0; i < t.nn; ++i) {
      const double mi = hgm(i * M + a);
      if (mi > 0)
        for (std::size_t r = 0; r < mem.size(); ++r) Sp[a](i, r) = t.S[a](r, i) * mp(r) / mi;
    }
    dv[a] = Eigen::MatrixXd::Zero(t.nn, 2);
    for (LO i = 0; i < t.nn; ++i)
      if (with_dv && hgm(i * M + a) > 0) {
        dv[a](i, 0) = u(rng);
        dv[a](i, 1) = u(rng);
      }
    va[a] = Sp[a] * V[a] + dv[a];
    for (LO i = 0; i < t.nn; ++i)
      for (int c = 0; c < 2; ++c) {
        hv1((i * M + a) * 2 + c) = va[a](i, c);
        hdv((i * M + a) * 2 + c) = dv[a](i, c);
      }
  }
  Kokkos::View<double*, MemSpace> v1("v1", ns * 2), dv1("dv1", ns * 2), vstar("vstar", ns * 2);
  Kokkos::deep_copy(v1, hv1);
  Kokkos::deep_copy(dv1, hdv);
  XpicScratch scratch;
  GridConstraints none;  // no constrained nodes
  StencilView<2, UGimp> sts;
  compute_stencils<2, UGimp>(t.g, t.p, sts);
  xpic_vstar<2, UGimp>(t.g, M, t.p, sts, t.gm, v1, dv1, order, none, vstar, scratch);
  auto hvs = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), vstar);
  double worst = 0, scale = 0;
  for (int a = 0; a < M; ++a) {
    const Eigen::Index n = V[a].rows();
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd A = I - t.S[a] * Sp[a];
    Eigen::MatrixXd Am = I, Am1 = I;
    for (int k = 0; k < order; ++k) Am = Am * A;
    for (int k = 0; k < order - 1; ++k) Am1 = Am1 * A;
    const Eigen::MatrixXd ref = (I - Am) * V[a] + Am1 * t.S[a] * dv[a];  // Eq. 37
    Eigen::MatrixXd vs(t.nn, 2);
    for (LO i = 0; i < t.nn; ++i)
      for (int c = 0; c < 2; ++c) vs(i, c) = hvs((i * M + a) * 2 + c);
    if (order == 1) EXPECT_EQ(vs.cwiseAbs().maxCoeff(), 0.0);  // XPIC(1): v* = 0
    const Eigen::MatrixXd got = order * t.S[a] * (va[a] - vs);  // Eq. 41
    worst = std::fmax(worst, (got - ref).cwiseAbs().maxCoeff());
    scale = std::fmax(scale, ref.cwiseAbs().maxCoeff());
    if (order == 1) EXPECT_LT((got - t.S[a] * va[a]).cwiseAbs().maxCoeff(), 1e-14);  // Eq. 38: PIC
  }
  EXPECT_LT(worst, 1e-12 * scale) << "M = " << M << " m = " << order << (with_dv ? " with" : " without")
                                   << " Delta v: max |kernel - Eq. 37| = " << worst;
}

TEST(ExplicitXpic, Xpic1IsPic) {
  check(1, 1, false, 3);
  check(2, 1, true, 4);
}

TEST(ExplicitXpic, VstarMatchesMatrixFormulaSingleMaterial) {
  for (int m = 2; m <= 6; ++m) check(1, m, false, 10 + m);
}

TEST(ExplicitXpic, VstarMatchesMatrixFormulaTwoMaterialsWithContactCorrection) {
  for (int m = 2; m <= 6; ++m) {
    check(2, m, false, 20 + m);
    check(2, m, true, 30 + m);
  }
}

}  // namespace
