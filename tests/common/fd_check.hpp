#pragma once
// Strict finite-difference check of an energy term (EnergyTerm<dim>), entry by
// entry, through the term's own assemble() into a Tpetra matrix on the term's
// own graph, in two variants:
//
//  1. all DOFs free: the assembled gradient against central differences of
//     energy(), and every entry of the assembled Hessian (the whole dense
//     n x n matrix: entries missing from the graph read 0) against central
//     differences of gradient();
//  2. some DOFs prescribed, as the DOF space's sink eliminates them
//     (kernels/dof_sink.hpp, src/solver/dof_space.cpp): the term
//     adds scale * dE/dx to every gradient entry, scale * H(free, free) to the
//     free rows and columns of A, nothing to a prescribed row or column (the
//     solver then puts an identity row there and rhs = dx_prescribed), and
//     rhs(free) -= scale * H(free, prescribed) dx_prescribed. Checked: the
//     free entries of the gradient against the energy restricted to the free
//     DOFs, A(free, free) against the Hessian of that restricted energy, every
//     stored entry of a prescribed row or column exactly 0, rhs(prescribed)
//     exactly 0 and rhs(free) against a central difference of the gradient
//     along dx_prescribed. This variant runs with scale != 1, so a missing
//     scale on a branch is seen too.
//
// Tolerance, per entry a (analytic) against f (central difference, step h):
//   |a - f| <= tol * max(|a|, |f|) + 4 |f_h - f_2h| + 8 eps (|f| + X S) / h.
// * tol * max(|a|, |f|): relative to the entry itself, not to the largest
//   entry, so a small block that is wrong by more than tol is seen however
//   large the rest of the matrix is. An entry that is exactly 0 analytically
//   has to come out ~0 by differences too (up to the two floors below).
// * 4 |f_h - f_2h|: the truncation error of the central difference,
//   c h^2 + O(h^4), estimated per entry from the same difference at 2h
//   (whose error is 4 c h^2: |f_h - f_2h| ~ 3 c h^2). A wrong analytic entry
//   does not move either difference, so this floor cannot hide a bug; it only
//   admits the curvature of the term (barrier, friction mollifier) at h.
// * a round-off floor, 8 eps (|f| + X S) / h: what a difference quotient of
//   computed values cannot resolve. The energy and the gradient are computed
//   backward-stably (as the exact function of inputs perturbed by ~eps |x|),
//   so a computed value f carries an error of about eps (|f| + X S), where
//   X = |x| over the DOFs it depends on and S = the sum of |its derivatives|
//   (for a gradient entry: |E| and X = |x|_inf, S = sum_j |g_j|; for a
//   Hessian or rhs entry in row i: |grad_i| and X = max |x_j| over row i's
//   couplings, S = sum_j |H_ij| by differences). This is per row, scaled to
//   the row's own entries and to the step, not to the largest entry of the
//   matrix. It matters where a gradient entry is a small difference of large
//   terms: e.g. the x component of a barrier force under a nearly horizontal
//   edge, (p - c)_x ~ 1e-4 formed from coordinates ~ 1, whose xx Hessian
//   entries (~ n_x^2 ~ 1e-5 of the row's largest) a step h = 1e-7 resolves only
//   to ~0.5 % (measured: h = 1e-6 resolves them to 1e-5).
// The term must be smooth within +-2h of x (no case or branch change there),
// and a term with a PSD projection must have it switched off by the caller.
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "solver/dof_graph.hpp"
#include "solver/energy_term.hpp"

namespace bfemp::fixtures {

namespace fd_detail {

using HostVec = std::vector<double>;

// Central differences of energy() (gradient) and gradient() (Hessian
// columns) at steps h and 2h, and of gradient() along a direction.
template <int dim>
struct FdReference {
  std::size_t nd = 0;
  HostVec g_h, g_2h;   // dE/dx_i
  HostVec H_h, H_2h;   // d grad_i / dx_j, row-major nd x nd
  double e_scale = 0;  // largest |E| evaluated
  HostVec g_scale;     // per row i: largest |grad_i| evaluated
};

inline void copy_to_host(Kokkos::View<double*, MemSpace> v, HostVec& out) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  out.assign(h.data(), h.data() + h.extent(0));
}

// Gradient of the term at x, scale 1.
template <int dim>
HostVec gradient_at(const EnergyTerm<dim>& term, Kokkos::View<double*, MemSpace> x) {
  Kokkos::View<double*, MemSpace> g("fd_g", x.extent(0));
  term.gradient(x, 1.0, g);
  Kokkos::fence();
  HostVec out;
  copy_to_host(g, out);
  return out;
}

// x(i) <- value (host copy kept in step with the view).
inline void set_entry(Kokkos::View<double*, MemSpace> x, std::size_t i, double value) {
  auto sub = Kokkos::subview(x, i);
  Kokkos::deep_copy(sub, value);
}

template <int dim>
FdReference<dim> fd_reference(const EnergyTerm<dim>& term, Kokkos::View<double*, MemSpace> x, double h) {
  FdReference<dim> r;
  const std::size_t nd = x.extent(0);
  r.nd = nd;
  r.g_h.assign(nd, 0.0);
  r.g_2h.assign(nd, 0.0);
  r.H_h.assign(nd * nd, 0.0);
  r.H_2h.assign(nd * nd, 0.0);
  r.g_scale.assign(nd, 0.0);
  Kokkos::View<double*, Kokkos::HostSpace> xh("fd_x", nd);  // a copy, not a mirror (which could alias x)
  Kokkos::deep_copy(xh, x);
  for (std::size_t j = 0; j < nd; ++j) {
    const double x0 = xh(j);
    double e[4];
    HostVec g[4];
    const double steps[4] = {h, -h, 2 * h, -2 * h};
    for (int k = 0; k < 4; ++k) {
      set_entry(x, j, x0 + steps[k]);
      e[k] = term.energy(x);
      g[k] = gradient_at<dim>(term, x);
      r.e_scale = std::max(r.e_scale, std::abs(e[k]));
      for (std::size_t i = 0; i < nd; ++i) r.g_scale[i] = std::max(r.g_scale[i], std::abs(g[k][i]));
    }
    set_entry(x, j, x0);
    r.g_h[j] = (e[0] - e[1]) / (2 * h);
    r.g_2h[j] = (e[2] - e[3]) / (4 * h);
    for (std::size_t i = 0; i < nd; ++i) {
      r.H_h[i * nd + j] = (g[0][i] - g[1][i]) / (2 * h);
      r.H_2h[i * nd + j] = (g[2][i] - g[3][i]) / (4 * h);
    }
  }
  return r;
}

// Central differences of the gradient along direction d (x + s d), steps h, 2h.
template <int dim>
void fd_directional(const EnergyTerm<dim>& term, Kokkos::View<double*, MemSpace> x, const HostVec& d, double h,
                    HostVec& dg_h, HostVec& dg_2h, HostVec& g_scale) {
  const std::size_t nd = x.extent(0);
  g_scale.assign(nd, 0.0);
  // Separate host copies (a host mirror of a host view would alias x).
  Kokkos::View<double*, Kokkos::HostSpace> x0("fd_x0", nd), xs("fd_xs", nd);
  Kokkos::deep_copy(x0, x);
  HostVec g[4];
  const double steps[4] = {h, -h, 2 * h, -2 * h};
  for (int k = 0; k < 4; ++k) {
    for (std::size_t i = 0; i < nd; ++i) xs(i) = x0(i) + steps[k] * d[i];
    Kokkos::deep_copy(x, xs);
    g[k] = gradient_at<dim>(term, x);
    for (std::size_t i = 0; i < nd; ++i) g_scale[i] = std::max(g_scale[i], std::abs(g[k][i]));
  }
  Kokkos::deep_copy(x, x0);
  dg_h.assign(nd, 0.0);
  dg_2h.assign(nd, 0.0);
  for (std::size_t i = 0; i < nd; ++i) {
    dg_h[i] = (g[0][i] - g[1][i]) / (2 * h);
    dg_2h[i] = (g[2][i] - g[3][i]) / (4 * h);
  }
}

// The term's assemble() on its own graph, as a dense host matrix; `stored`
// marks the entries the graph has.
struct Assembled {
  HostVec grad, rhs, A;
  std::vector<char> stored;
};

template <int dim>
Assembled assemble_dense(const EnergyTerm<dim>& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double scale,
                         const std::vector<int>& mask, const HostVec& dx_prescribed, bool project = true,
                         double contact_keep = 0.0) {
  const std::size_t nd = static_cast<std::size_t>(n_nodes) * dim;
  auto map = Teuchos::rcp(new Map(nd, 0, Tpetra::getDefaultComm()));
  auto A = Teuchos::rcp(new Matrix(build_dof_graph<dim>({&term}, n_nodes, map)));
  A->fillComplete();
  A->resumeFill();
  A->setAllToScalar(0.0);
  Kokkos::View<double*, MemSpace> grad("fd_grad", nd), rhs("fd_rhs", nd), dxp("fd_dxp", nd);
  Kokkos::View<int*, MemSpace> pres("fd_pres", nd);
  {
    auto ph = Kokkos::create_mirror_view(pres);
    auto dh = Kokkos::create_mirror_view(dxp);
    for (std::size_t i = 0; i < nd; ++i) {
      ph(i) = mask.empty() ? 0 : mask[i];
      dh(i) = dx_prescribed.empty() ? 0.0 : dx_prescribed[i];
    }
    Kokkos::deep_copy(pres, ph);
    Kokkos::deep_copy(dxp, dh);
  }
  auto sink = make_sink<dim>(A->getLocalMatrixDevice(), scale, grad, rhs, pres, dxp);
  sink.project = project;
  sink.contact_keep = contact_keep;
  term.assemble(x, sink);
  Kokkos::fence();
  A->fillComplete();
  Assembled out;
  copy_to_host(grad, out.grad);
  copy_to_host(rhs, out.rhs);
  out.A.assign(nd * nd, 0.0);
  out.stored.assign(nd * nd, 0);
  for (std::size_t i = 0; i < nd; ++i) {
    const std::size_t len = A->getNumEntriesInLocalRow(i);
    typename Matrix::nonconst_local_inds_host_view_type cols("c", len);
    typename Matrix::nonconst_values_host_view_type vals("v", len);
    size_t n = 0;
    A->getLocalRowCopy(i, cols, vals, n);
    for (size_t k = 0; k < n; ++k) {
      const auto j = static_cast<std::size_t>(A->getColMap()->getGlobalElement(cols(k)));
      out.A[i * nd + j] += vals(k);
      out.stored[i * nd + j] = 1;
    }
  }
  return out;
}

// Collects the entries over tolerance and reports the worst few.
class EntryChecker {
 public:
  EntryChecker(std::string what, double tol) : what_(std::move(what)), tol_(tol) {}
  // a: analytic, f: difference at h, f2: at 2h, roundoff: the difference's
  // round-off floor for this entry.
  void check(const std::string& where, double a, double f, double f2, double roundoff) {
    ++checked_;
    const double allowed = tol_ * std::max(std::abs(a), std::abs(f)) + 4 * std::abs(f - f2) + roundoff;
    const double err = std::abs(a - f);
    if (!(err <= allowed)) add(where, a, f, err, allowed);
  }
  // Must be exactly 0 (an eliminated row or column, an rhs of a prescribed DOF).
  void check_zero(const std::string& where, double a) {
    ++checked_;
    if (a != 0.0) add(where, a, 0.0, std::abs(a), 0.0);
  }
  void report() const {
    if (failures_ == 0) return;
    std::ostringstream s;
    s << what_ << ": " << failures_ << " of " << checked_ << " entries over tolerance (tol " << tol_
      << " relative per entry); worst:";
    for (const auto& w : worst_) s << "\n  " << w.second;
    ADD_FAILURE() << s.str();
  }
  std::size_t failures() const { return failures_; }

 private:
  void add(const std::string& where, double a, double f, double err, double allowed) {
    ++failures_;
    const double ratio = allowed > 0 ? err / allowed : std::numeric_limits<double>::infinity();
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s: analytic %.10g, expected %.10g, |error| %.3g, allowed %.3g", where.c_str(), a, f,
                  err, allowed);
    worst_.emplace_back(ratio, buf);
    std::sort(worst_.begin(), worst_.end(), [](const auto& l, const auto& r) { return l.first > r.first; });
    if (worst_.size() > 12) worst_.resize(12);
  }
  std::string what_;
  double tol_;
  std::size_t checked_ = 0, failures_ = 0;
  std::vector<std::pair<double, std::string>> worst_;
};

inline std::string at(const char* name, std::size_t i) { return std::string(name) + "(" + std::to_string(i) + ")"; }
inline std::string at(const char* name, std::size_t i, std::size_t j) {
  return std::string(name) + "(" + std::to_string(i) + ", " + std::to_string(j) + ")";
}

}  // namespace fd_detail

// DOFs the checks prescribe by default: among the DOFs the term couples (a
// nonzero FD Hessian row), every third one and every component of one node
// in the middle of them, so that free-prescribed couplings occur within
// nodes and across nodes and stencils.
template <int dim>
std::vector<int> default_prescribed_dofs(const fd_detail::FdReference<dim>& ref) {
  const std::size_t nd = ref.nd;
  std::vector<std::size_t> active;
  for (std::size_t i = 0; i < nd; ++i) {
    bool nz = false;
    for (std::size_t j = 0; j < nd && !nz; ++j) nz = ref.H_h[i * nd + j] != 0.0;
    if (nz) active.push_back(i);
  }
  std::vector<int> mask(nd, 0);
  for (std::size_t k = 1; k < active.size(); k += 3) mask[active[k]] = 1;
  if (!active.empty()) {
    const std::size_t node = active[active.size() / 2] / dim;
    for (int c = 0; c < dim; ++c) mask[node * dim + c] = 1;
  }
  return mask;
}

// Runs both variants (all free; `mask` prescribed, default_prescribed_dofs
// when empty). fd_h: the difference step; tol: relative tolerance per entry.
template <int dim>
inline void check_energy_term(const EnergyTerm<dim>& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double fd_h,
                              double tol, std::vector<int> mask = {}) {
  using namespace fd_detail;
  const std::size_t nd = static_cast<std::size_t>(n_nodes) * dim;
  ASSERT_EQ(x.extent(0), nd);
  const double eps = std::numeric_limits<double>::epsilon();
  const FdReference<dim> ref = fd_reference<dim>(term, x, fd_h);
  // Round-off floors (see the tolerance note at the top): the energy and the
  // gradient are evaluated backward-stably, i.e. as the exact function at
  // inputs perturbed by ~eps |x|, so a computed value carries an error of
  // about eps (|value| + |x| |its derivative|), and a difference quotient
  // with step h that error over h.
  double x_max = 0, g_sum = 0;
  {
    Kokkos::View<double*, Kokkos::HostSpace> xh("fd_xmax", nd);
    Kokkos::deep_copy(xh, x);
    for (std::size_t i = 0; i < nd; ++i) x_max = std::max(x_max, std::abs(xh(i)));
    for (std::size_t i = 0; i < nd; ++i) g_sum += std::abs(ref.g_h[i]);
  }
  const double g_round = 8 * eps * (ref.e_scale + x_max * g_sum) / fd_h;
  std::vector<double> row_round(nd, 0.0);  // row i of the Hessian (and of the rhs)
  {
    Kokkos::View<double*, Kokkos::HostSpace> xh("fd_xrow", nd);
    Kokkos::deep_copy(xh, x);
    for (std::size_t i = 0; i < nd; ++i) {
      double row_sum = 0, x_row = std::abs(xh(i));
      for (std::size_t j = 0; j < nd; ++j) {
        const double hij = std::abs(ref.H_h[i * nd + j]);
        row_sum += hij;
        if (hij != 0) x_row = std::max(x_row, std::abs(xh(j)));
      }
      row_round[i] = 8 * eps * (ref.g_scale[i] + x_row * row_sum) / fd_h;
    }
  }
  auto h_round = [&](std::size_t i) { return row_round[i]; };
  std::size_t nonzero = 0;
  for (double v : ref.H_h) nonzero += v != 0.0;
  ASSERT_GT(nonzero, 0u) << "the term has no Hessian at x: nothing is checked";

  {  // 1. all DOFs free, scale 1
    SCOPED_TRACE("all DOFs free");
    const Assembled as = assemble_dense<dim>(term, n_nodes, x, 1.0, {}, {});
    EntryChecker cg("gradient", tol), ch("Hessian", tol), cr("rhs", tol);
    for (std::size_t i = 0; i < nd; ++i) cg.check(at("g", i), as.grad[i], ref.g_h[i], ref.g_2h[i], g_round);
    for (std::size_t i = 0; i < nd; ++i)
      for (std::size_t j = 0; j < nd; ++j)
        ch.check(at("H", i, j), as.A[i * nd + j], ref.H_h[i * nd + j], ref.H_2h[i * nd + j], h_round(i));
    for (std::size_t i = 0; i < nd; ++i) cr.check_zero(at("rhs", i), as.rhs[i]);
    cg.report();
    ch.report();
    cr.report();
  }

  {  // 2. some DOFs prescribed, scale != 1
    if (mask.empty()) mask = default_prescribed_dofs<dim>(ref);
    ASSERT_EQ(mask.size(), nd);
    const std::size_t n_pres = std::count(mask.begin(), mask.end(), 1);
    ASSERT_GT(n_pres, 0u);
    ASSERT_LT(n_pres, nd);
    std::ostringstream trace;
    trace << n_pres << " of " << nd << " DOFs prescribed";
    SCOPED_TRACE(trace.str());
    const double scale = 0.375;  // like the time-step factor h the solver passes
    // dx_prescribed: O(1) values of both signs on the prescribed DOFs.
    HostVec dxp(nd, 0.0);
    for (std::size_t i = 0; i < nd; ++i)
      if (mask[i]) dxp[i] = (i % 2 ? -1.0 : 1.0) * (0.5 + 0.5 * std::fmod(0.6180339887 * (i + 1), 1.0));
    HostVec dg_h, dg_2h;
    HostVec dg_scale;
    fd_directional<dim>(term, x, dxp, fd_h, dg_h, dg_2h, dg_scale);
    const Assembled as = assemble_dense<dim>(term, n_nodes, x, scale, mask, dxp);
    EntryChecker cg("gradient (prescribed variant)", tol);
    EntryChecker ch("Hessian of the energy restricted to the free DOFs", tol);
    EntryChecker cz("entries of prescribed rows / columns (must be 0)", 0);
    EntryChecker cr("rhs = -scale H(free, prescribed) dx_prescribed", tol);
    for (std::size_t i = 0; i < nd; ++i)
      cg.check(at("g", i), as.grad[i], scale * ref.g_h[i], scale * ref.g_2h[i], scale * g_round);
    for (std::size_t i = 0; i < nd; ++i)
      for (std::size_t j = 0; j < nd; ++j) {
        const double a = as.A[i * nd + j];
        if (mask[i] || mask[j]) {
          if (as.stored[i * nd + j]) cz.check_zero(at("A", i, j), a);
        } else {
          ch.check(at("H", i, j), a, scale * ref.H_h[i * nd + j], scale * ref.H_2h[i * nd + j], scale * h_round(i));
        }
      }
    for (std::size_t i = 0; i < nd; ++i) {
      if (mask[i])
        cz.check_zero(at("rhs", i), as.rhs[i]);
      else
        cr.check(at("rhs", i), as.rhs[i], -scale * dg_h[i], -scale * dg_2h[i],
                 scale * (h_round(i) + 8 * eps * dg_scale[i] / fd_h));
    }
    cg.report();
    ch.report();
    cz.report();
    cr.report();
  }
}

// The sink's `project` flag (Newton/hessian: exact-if-definite): the term,
// with its own projection on, assembled through a sink with project = false
// must give the Hessian and
// gradient of the term with its projection switched off, which
// check_energy_term verifies against differences. Returns the number of
// Hessian entries where the projected assembly differs from the exact one:
// a case must have some for this check to show anything. Leaves the term's
// projection on.
template <int dim, class Term>
std::size_t check_sink_exact_hessian(Term& term, LO n_nodes, Kokkos::View<double*, MemSpace> x) {
  using namespace fd_detail;
  term.set_projection(false);
  const Assembled exact = assemble_dense<dim>(term, n_nodes, x, 1.0, {}, {});
  term.set_projection(true);
  const Assembled via_sink = assemble_dense<dim>(term, n_nodes, x, 1.0, {}, {}, false);
  const Assembled projected = assemble_dense<dim>(term, n_nodes, x, 1.0, {}, {}, true);
  std::size_t differ = 0, mismatch = 0;
  double a_max = 0, g_max = 0;
  for (double v : exact.A) a_max = std::max(a_max, std::abs(v));
  for (double v : exact.grad) g_max = std::max(g_max, std::abs(v));
  // Equal up to the order of atomic sums (uncolored terms on several threads).
  const auto same = [](double a, double b, double floor) { return std::abs(a - b) <= 1e-13 * std::abs(a) + floor; };
  for (std::size_t k = 0; k < exact.A.size(); ++k) {
    mismatch += !same(via_sink.A[k], exact.A[k], 1e-15 * a_max);
    differ += std::abs(projected.A[k] - exact.A[k]) > 1e-9 * std::abs(exact.A[k]) + 1e-300;
  }
  for (std::size_t i = 0; i < exact.grad.size(); ++i) mismatch += !same(via_sink.grad[i], exact.grad[i], 1e-15 * g_max);
  EXPECT_EQ(mismatch, 0u) << "assembling through a sink with project = false differs from the exact Hessian";
  return differ;
}

// A term whose local Hessians can be indefinite (barrier contact: b' grad^2 d;
// lagged friction: its compensation pairs, mu lambda < 0): with its
// projection off, its energy must be positive at x (the case is in contact),
// gradient and Hessian must match differences entry by entry, and the sink's
// project = false path must give that exact Hessian, which the projection
// changes somewhere. Leaves the projection on.
template <int dim, class Term>
void check_exact_term(Term& term, LO n_nodes, Kokkos::View<double*, MemSpace> x, double fd_h, double tol) {
  term.set_projection(false);
  ASSERT_GT(term.energy(x), 0.0) << "the case has no active pair";
  check_energy_term<dim>(term, n_nodes, x, fd_h, tol);
  EXPECT_GT(check_sink_exact_hessian<dim>(term, n_nodes, x), 0u) << "the projection changes nothing here";
}

}  // namespace bfemp::fixtures
