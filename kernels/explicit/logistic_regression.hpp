#pragma once
// Logistic-regression (LR) contact normal and separation of paper 001 §3.1 and
// the appendix (Eqs. 19-25, 53-57).
//
// Point cloud: positions X_p (here relative to the contact node, which only
// moves the offset phi_{dim+1}; it has no penalty, so the fit is unchanged)
// with classes c_p = -1 (material alpha) or +1 (beta). With x_p = (X_p, 1):
//   f(x, phi) = 2 / (1 + exp(-x.phi)) - 1 = tanh(x.phi / 2)              (Eq. 20)
//   psi(x)    = 2 e / (1 + e)^2 = (1 - f^2) / 2,  e = exp(-x.phi)          (Eq. 53)
//   phi^(k+1) = phi^(k) + (J^T W J + Lambda)^-1 (J^T W (c - f) - Lambda phi^(k))  (Eq. 21)
//   (J^T W J)_kl = sum_p psi^2 w_p x_pk x_pl, (J^T W (c - f))_j = sum_p psi w_p (c_p - f_p) x_pj
// exactly as the appendix: phi^(0) = 0 (so phi^(1) is the linear regression),
// w_p = 1, Lambda = 1e-7 dx^2 diag(1, 1, (1,) 0), stop when
// 1 - n^(k+1).n^(k) < 1e-5 (about 0.0044 rad) or after 15 iterations (the
// last iterate is used). n = phi_{1..dim} / |phi_{1..dim}| points from alpha
// to beta.
//
// Separation (Eqs. 22-24): d_LR = min_{p in beta}(X_p.n - R_p) - max_{p in alpha}(X_p.n + R_p),
// contact needs d_LR < 0. R_p (Eq. 25): the distance along n from particle p's
// centre to its deformed inscribed ellipsoid,
//   1 / R_p = sqrt( sum_d n0_d^2 / R0_d^2 ),  n0 = F_p^-1 n
// (R0: the undeformed semi-axes, i.e. half the particle's sides; m).
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"

namespace bfemp::xmpm {

struct LRSettings {
  double tolerance = 1e-5;  // on 1 - n^(k+1).n^(k)
  int max_iterations = 15;
  double penalty = 1e-7;    // lambda = penalty dx^2 on the normal components
  // Contact when d_LR < contact_tolerance * dx (0: the paper's d_LR < 0).
  // Particles of two blocks in contact touch exactly, so d_LR is 0 up to a
  // drift of 1e-9..3e-6 m (B1(b), PIC, interface mid-cell near 4.5 % strain);
  // a node falsely 'separated' leaves the minority class (8-18 % of the node
  // mass) free, a ~ 1e8 m/s^2 (~130 m/s in one step), and the kick, the
  // interpenetration and the release repeat until PIC blows up at 5.5 %.
  // 1e-3 removes that (a 5 um gap at 5 mm cells: 0.07 % of B1(a)'s 7.5 mm gap).
  double contact_tolerance = 0.0;
};

template <int dim>
struct LRResult {
  Vec<dim> normal = Vec<dim>::Zero();  // unit, alpha -> beta (zero if the fit failed)
  double offset = 0;                   // phi_{dim+1}
  int iterations = 0;
  bool converged = false;
};

// Solves A y = b in place (n x n, partial pivoting); a pivot below 1e-300
// leaves that component of y zero.
template <int n>
KOKKOS_INLINE_FUNCTION void small_solve(double (&A)[n][n], double (&b)[n], double (&y)[n]) {
  for (int k = 0; k < n; ++k) {
    int piv = k;
    for (int i = k + 1; i < n; ++i)
      if (std::fabs(A[i][k]) > std::fabs(A[piv][k])) piv = i;
    if (piv != k) {
      for (int j = 0; j < n; ++j) {
        const double t = A[k][j];
        A[k][j] = A[piv][j];
        A[piv][j] = t;
      }
      const double t = b[k];
      b[k] = b[piv];
      b[piv] = t;
    }
    if (std::fabs(A[k][k]) < 1e-300) continue;
    for (int i = k + 1; i < n; ++i) {
      const double f = A[i][k] / A[k][k];
      for (int j = k; j < n; ++j) A[i][j] -= f * A[k][j];
      b[i] -= f * b[k];
    }
  }
  for (int k = n - 1; k >= 0; --k) {
    if (std::fabs(A[k][k]) < 1e-300) {
      y[k] = 0;
      continue;
    }
    double s = b[k];
    for (int j = k + 1; j < n; ++j) s -= A[k][j] * y[j];
    y[k] = s / A[k][k];
  }
}

// The NLLS fit. for_each(g) must call g(const Vec<dim>& X_rel, double c) for
// every point of the cloud (c = -1 alpha, +1 beta); it is called once per
// iteration. dx: grid cell size (m).
template <int dim, class ForEach>
KOKKOS_INLINE_FUNCTION LRResult<dim> lr_fit(const ForEach& for_each, double dx, const LRSettings& s = {}) {
  constexpr int n = dim + 1;
  double phi[n] = {};
  LRResult<dim> r;
  Vec<dim> prev = Vec<dim>::Zero();
  const double lam = s.penalty * dx * dx;
  for (int it = 1; it <= s.max_iterations; ++it) {
    double A[n][n] = {}, b[n] = {}, y[n];
    for (int j = 0; j < dim; ++j) {
      A[j][j] = lam;
      b[j] = -lam * phi[j];
    }
    for_each([&](const Vec<dim>& X, double c) {
      double xh[n];
      double z = phi[dim];
      for (int j = 0; j < dim; ++j) {
        xh[j] = X(j);
        z += X(j) * phi[j];
      }
      xh[dim] = 1.0;
      const double f = std::tanh(0.5 * z);
      const double psi = 0.5 * (1.0 - f * f);
      const double psi2 = psi * psi, rhs = psi * (c - f);
      for (int k = 0; k < n; ++k) {
        b[k] += rhs * xh[k];
        for (int l = 0; l < n; ++l) A[k][l] += psi2 * xh[k] * xh[l];
      }
    });
    small_solve<n>(A, b, y);
    for (int k = 0; k < n; ++k) phi[k] += y[k];
    Vec<dim> nn;
    for (int j = 0; j < dim; ++j) nn(j) = phi[j];
    const double len = nn.norm();
    r.iterations = it;
    if (!(len > 0.0) || !std::isfinite(len)) {  // no direction: keep the previous one
      r.normal = prev;
      break;
    }
    nn /= len;
    r.normal = nn;
    r.offset = phi[dim];
    if (it > 1 && 1.0 - nn.dot(prev) < s.tolerance) {
      r.converged = true;
      break;
    }
    prev = nn;
  }
  return r;
}

// R_p of Eq. 25 for a particle with deformation gradient F and undeformed
// semi-axes R0 (m), along the unit normal n.
template <int dim>
KOKKOS_INLINE_FUNCTION double ellipsoid_radius(const Mat<dim>& F, const Vec<dim>& R0, const Vec<dim>& n) {
  const Vec<dim> n0 = F.inverse() * n;
  double s = 0;
  for (int d = 0; d < dim; ++d) s += n0(d) * n0(d) / (R0(d) * R0(d));
  return 1.0 / std::sqrt(s);
}

}  // namespace bfemp::xmpm
