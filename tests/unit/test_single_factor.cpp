// SingleFactor (solver/single_factor.hpp): a float copy of a supernodal
// CHOLMOD factor L (L L^T = P A P^T), applied in double arithmetic.
// Asserted:
//  - solve(b) is the exact inverse of P^T L_f L_f^T P, L_f = L rounded to
//    float: the product with that operator, computed here entry by entry from
//    the factor (a multiplication, not a solve), gives b back to double
//    round-off (no worse than CHOLMOD's double solve for its factor), on a 3D Laplacian with a random diagonal and rows scaled over
//    six decades;
//  - the operator is symmetric (u^T M^-1 v = v^T M^-1 u);
//  - it differs from CHOLMOD's double solve by the float rounding, no more
//    (relative 1e-9 .. 1e-4 on this matrix);
//  - b and z may be one array;
//  - the solve on 2, 3 and 4 threads (disjoint subtrees per thread, the top
//    of the tree shared by panels) is the same operator: it gives the
//    one-thread answer to round-off, the same bits on every call and with a
//    team of one thread, and is as exact an inverse of the rounded factor;
//  - a simplicial factor, a symbolic one, and one whose entries leave float's
//    range are refused (assign false, nothing kept).
#include <gtest/gtest.h>

#include <cholmod.h>
#include <omp.h>

#include <cmath>
#include <random>
#include <vector>

#include "solver/cholmod_views.hpp"
#include "solver/single_factor.hpp"

namespace {

using bfemp::SingleFactor;
using Long = SuiteSparse_long;

struct Csc {  // both triangles, sorted columns (a symmetric matrix)
  std::vector<Long> p, i;
  std::vector<double> x;
  Long n = 0;
};

// 7-point Laplacian on side^3 nodes + diag(shift), then D A D with D_i = 10^(6 u_i - 3).
Csc laplacian3d(int side, double scale = 1.0) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = side * side * side;
  std::vector<double> d(n), shift(n);
  for (int k = 0; k < n; ++k) d[k] = scale * std::pow(10.0, 6.0 * u(rng) - 3.0), shift[k] = 0.01 + u(rng);
  Csc a;
  a.n = n;
  a.p.push_back(0);
  for (int c = 0; c < n; ++c) {
    const int x = c % side, y = (c / side) % side, z = c / (side * side);
    const int nb[7] = {z > 0 ? c - side * side : -1, y > 0 ? c - side : -1, x > 0 ? c - 1 : -1, c,
                       x + 1 < side ? c + 1 : -1, y + 1 < side ? c + side : -1,
                       z + 1 < side ? c + side * side : -1};
    for (int r : nb) {
      if (r < 0) continue;
      a.i.push_back(r);
      a.x.push_back((r == c ? 6.0 + shift[c] : -1.0) * d[r] * d[c]);
    }
    a.p.push_back(static_cast<Long>(a.i.size()));
  }
  return a;
}

cholmod_sparse view(Csc& a) { return bfemp::symmetric_csc_view(a.p, a.i, a.x.data()); }

struct Cholmod {
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  explicit Cholmod(int supernodal) {
    cholmod_l_start(&c);
    c.print = 0;
    c.supernodal = supernodal;
  }
  ~Cholmod() {
    if (L) cholmod_l_free_factor(&L, &c);
    cholmod_l_finish(&c);
  }
  void factorise(Csc& a) {
    cholmod_sparse S = view(a);
    L = cholmod_l_analyze(&S, &c);
    ASSERT_NE(L, nullptr);
    ASSERT_TRUE(cholmod_l_factorize(&S, L, &c));
    ASSERT_EQ(c.status, CHOLMOD_OK);
  }
  std::vector<double> solve(std::vector<double> b) {
    cholmod_dense B{};
    B.nrow = B.nzmax = B.d = b.size();
    B.ncol = 1;
    B.x = b.data();
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* X = cholmod_l_solve(CHOLMOD_A, L, &B, &c);
    std::vector<double> x(static_cast<double*>(X->x), static_cast<double*>(X->x) + b.size());
    cholmod_l_free_dense(&X, &c);
    return x;
  }
};

// P^T L_f L_f^T P z in long double, L_f the factor's entries rounded to float
// (round = false: the double entries themselves).
std::vector<double> apply_factor(const cholmod_factor& L, const std::vector<double>& z, bool round = true) {
  const auto* super = static_cast<const Long*>(L.super);
  const auto* pi = static_cast<const Long*>(L.pi);
  const auto* px = static_cast<const Long*>(L.px);
  const auto* s = static_cast<const Long*>(L.s);
  const auto* perm = static_cast<const Long*>(L.Perm);
  const auto* lx = static_cast<const double*>(L.x);
  const std::size_t n = L.n;
  std::vector<long double> w(n), y(n, 0.0L), u(n, 0.0L);
  for (std::size_t i = 0; i < n; ++i) w[i] = z[perm[i]];
  auto entry = [&](std::size_t k, Long i, Long j) {
    const double e = lx[px[k] + i + j * (pi[k + 1] - pi[k])];
    return round ? static_cast<long double>(static_cast<float>(e)) : static_cast<long double>(e);
  };
  for (std::size_t k = 0; k < L.nsuper; ++k)  // y = L_f^T w (the upper part of each stored column is not L)
    for (Long j = 0; j < super[k + 1] - super[k]; ++j)
      for (Long i = j; i < pi[k + 1] - pi[k]; ++i) y[super[k] + j] += entry(k, i, j) * w[s[pi[k] + i]];
  for (std::size_t k = 0; k < L.nsuper; ++k)  // u = L_f y
    for (Long j = 0; j < super[k + 1] - super[k]; ++j)
      for (Long i = j; i < pi[k + 1] - pi[k]; ++i) u[s[pi[k] + i]] += entry(k, i, j) * y[super[k] + j];
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[perm[i]] = static_cast<double>(u[i]);
  return r;
}

double norm(const std::vector<double>& v) {
  double s = 0;
  for (double a : v) s += a * a;
  return std::sqrt(s);
}

double diff(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t k = 0; k < a.size(); ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s);
}

std::vector<double> random_vector(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<double> v(n);
  for (double& a : v) a = g(rng);
  return v;
}

TEST(SingleFactor, SolvesWithTheFloatRoundedFactorExactlyAndSymmetrically) {
  Csc a = laplacian3d(14);
  Cholmod ch(CHOLMOD_SUPERNODAL);
  ch.factorise(a);
  ASSERT_TRUE(ch.L->is_super);
  ASSERT_GT(ch.L->nsuper, 10u) << "several supernodes, so the updates between them are exercised";
  SingleFactor f;
  ASSERT_TRUE(f.assign(*ch.L));
  EXPECT_EQ(f.entries(), ch.L->xsize);
  const std::size_t n = a.n;
  const auto b = random_vector(n, 3);
  std::vector<double> z(n);
  f.solve(b.data(), z.data());
  // The inverse of the float factor's operator, as exact as CHOLMOD's double
  // solve is for its own factor (the rows' 1e6 scale spread makes both
  // residuals ~1e-12 |b|, not 1e-16).
  const auto back = apply_factor(*ch.L, z);
  const auto x = ch.solve(b);
  const double cholmod_residual = diff(apply_factor(*ch.L, x, false), b);
  EXPECT_LT(diff(back, b), 10 * cholmod_residual + 1e-15 * norm(b))
      << "solve is (P^T L_f L_f^T P)^-1 up to double round-off";
  EXPECT_LT(cholmod_residual, 1e-10 * norm(b));
  // Not the double factor's inverse: the rounding shows, and only the rounding.
  const double rel = diff(z, x) / norm(x);
  EXPECT_GT(rel, 1e-9) << "the copy is rounded to float";
  EXPECT_LT(rel, 1e-4);
  std::cout << "single factor: |z - z_double| / |z_double| = " << rel << ", " << ch.L->nsuper << " supernodes, "
            << f.entries() << " entries; residual " << diff(back, b) / norm(b) << " (CHOLMOD's double solve "
            << cholmod_residual / norm(b) << ")\n";
  // Symmetric.
  const auto u = random_vector(n, 5), v = random_vector(n, 6);
  std::vector<double> mu(n), mv(n);
  f.solve(u.data(), mu.data());
  f.solve(v.data(), mv.data());
  double umv = 0, vmu = 0;
  for (std::size_t k = 0; k < n; ++k) umv += u[k] * mv[k], vmu += v[k] * mu[k];
  EXPECT_NEAR(umv, vmu, 1e-12 * std::abs(umv));
  // In place.
  std::vector<double> inplace = b;
  f.solve(inplace.data(), inplace.data());
  EXPECT_EQ(inplace, z);
}

TEST(SingleFactor, ThreadedSolveIsTheSameOperatorAsTheSerialOne) {
  Csc a = laplacian3d(20);
  Cholmod ch(CHOLMOD_SUPERNODAL);
  ch.factorise(a);
  SingleFactor f;
  ASSERT_TRUE(f.assign(*ch.L));
  const std::size_t n = a.n;
  const auto b = random_vector(n, 7);
  std::vector<double> z1(n);
  f.solve(b.data(), z1.data(), 1);
  EXPECT_EQ(f.schedule().threads, 0) << "one thread: no schedule";
  const auto x = ch.solve(b);
  const double cholmod_residual = diff(apply_factor(*ch.L, x, false), b);
  for (int threads : {2, 3, 4}) {
    std::vector<double> z(n), again(n);
    f.solve(b.data(), z.data(), threads);
    const auto& s = f.schedule();
    ASSERT_EQ(s.threads, threads) << "the factor is in postorder, so the threaded solve ran";
    EXPECT_GE(s.order.size(), static_cast<std::size_t>(threads)) << "at least one subtree per thread";
    int shared = 0;
    for (char c : s.top_shared) shared += c;
    EXPECT_GT(shared, 0) << "a top supernode solved by the whole team (" << s.top.size() << " in the top)";
    EXPECT_LT(diff(z, z1), 1e-12 * norm(z1)) << threads << " threads";
    EXPECT_LT(diff(apply_factor(*ch.L, z), b), 10 * cholmod_residual + 1e-15 * norm(b)) << threads << " threads";
    f.solve(b.data(), again.data(), threads);
    EXPECT_EQ(again, z) << "deterministic at " << threads << " threads";
    std::vector<double> inplace = b;
    f.solve(inplace.data(), inplace.data(), threads);
    EXPECT_EQ(inplace, z);
    {  // inside a parallel region without nested parallelism OpenMP gives a team of 1: the same bits
      std::vector<double> nested(n);
      const int levels = omp_get_max_active_levels();
      omp_set_max_active_levels(1);
#pragma omp parallel num_threads(2)
      {
#pragma omp single
        f.solve(b.data(), nested.data(), threads);
      }
      omp_set_max_active_levels(levels);
      EXPECT_EQ(nested, z) << "a team of 1 for " << threads << " threads' schedule";
    }
    std::cout << threads << " threads: " << s.order.size() << " subtrees, " << s.top.size() << " top supernodes ("
              << shared << " shared), top " << s.top_fraction << " of the entries; |z - z_1| / |z_1| = "
              << diff(z, z1) / norm(z1) << "\n";
  }
}

// worth_copying: a copy into a new buffer after kWorthAfterGrowing solves, into
// the room this step's copies made (a factor no larger) after kWorthAfter;
// new_step() forgets the room.
TEST(SingleFactor, ACopyIsWorthItAfterTheSolvesThatPayForIt) {
  Csc small = laplacian3d(10), large = laplacian3d(12);
  Cholmod s(CHOLMOD_SUPERNODAL), l(CHOLMOD_SUPERNODAL);
  s.factorise(small);
  l.factorise(large);
  ASSERT_LT(s.L->xsize, l.L->xsize);
  SingleFactor f;
  EXPECT_FALSE(f.worth_copying(*s.L, SingleFactor::kWorthAfterGrowing - 1));
  EXPECT_TRUE(f.worth_copying(*s.L, SingleFactor::kWorthAfterGrowing));
  ASSERT_TRUE(f.assign(*s.L));
  f.clear();
  EXPECT_FALSE(f.worth_copying(*s.L, SingleFactor::kWorthAfter - 1));
  EXPECT_TRUE(f.worth_copying(*s.L, SingleFactor::kWorthAfter));
  if (l.L->xsize > s.L->xsize + s.L->xsize / 4) {  // beyond the headroom: the buffer grows
    EXPECT_FALSE(f.worth_copying(*l.L, SingleFactor::kWorthAfterGrowing - 1));
  }
  EXPECT_TRUE(f.worth_copying(*l.L, SingleFactor::kWorthAfterGrowing));
  // A new time step counts its own copies only (a restarted run has none).
  f.new_step();
  EXPECT_FALSE(f.worth_copying(*s.L, SingleFactor::kWorthAfterGrowing - 1));
  ASSERT_TRUE(f.assign(*s.L));
  EXPECT_TRUE(f.worth_copying(*s.L, SingleFactor::kWorthAfter));
}

TEST(SingleFactor, RefusesWhatItCannotCopy) {
  Csc a = laplacian3d(8);
  {
    Cholmod ch(CHOLMOD_SIMPLICIAL);
    ch.factorise(a);
    ASSERT_FALSE(ch.L->is_super);
    SingleFactor f;
    EXPECT_FALSE(f.assign(*ch.L));
    EXPECT_FALSE(f.ready());
  }
  {
    Cholmod ch(CHOLMOD_SUPERNODAL);
    cholmod_sparse S = view(a);
    ch.L = cholmod_l_analyze(&S, &ch.c);  // symbolic only
    SingleFactor f;
    EXPECT_FALSE(f.assign(*ch.L));
  }
  {
    Csc big = laplacian3d(8, 1e40);  // entries ~1e80, factor entries ~1e40 > FLT_MAX
    Cholmod ch(CHOLMOD_SUPERNODAL);
    ch.factorise(big);
    SingleFactor f;
    EXPECT_FALSE(f.assign(*ch.L));
    EXPECT_FALSE(f.ready());
    EXPECT_EQ(f.entries(), 0u);
    Cholmod ok(CHOLMOD_SUPERNODAL);  // a usable one after a refusal
    ok.factorise(a);
    EXPECT_TRUE(f.assign(*ok.L));
    EXPECT_TRUE(f.ready());
  }
}

}  // namespace
