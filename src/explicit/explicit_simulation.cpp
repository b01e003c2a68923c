// The explicit multimaterial MPM step; see explicit_simulation.hpp for the
// algorithm and its equations (paper 001).
#include "explicit/explicit_simulation.hpp"

#include <Kokkos_Timer.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "kernels/explicit/shape_functions.hpp"
#include "kernels/small_loops.hpp"
#include "materials/linear_elastic.hpp"
#include "materials/neo_hookean.hpp"

namespace bfemp {

using namespace xmpm;

namespace {

using DView = Kokkos::View<double*, MemSpace>;

template <int dim>
KOKKOS_INLINE_FUNCTION Mat<dim> x_cauchy(const XMaterial& m, const Mat<dim>& F) {
  if (m.model == XModel::HyperelasticKG) return m.kg.template cauchy<dim>(F);
  const Mat<dim> P = m.model == XModel::NeoHookean ? NeoHookean::first_piola<dim>(F, m.lame)
                                                   : LinearElastic::first_piola<dim>(F, m.lame);
  return P * F.transpose() / F.determinant();
}

// Current dilatational wave speed (m/s): sqrt(M_t J / rho0) with the tangent
// P-wave modulus M_t (Eq. 18: K/2 (J + 1/J) + 4/3 G J^(-5/3); others: lambda + 2 mu).
KOKKOS_INLINE_FUNCTION double x_wave_speed(const XMaterial& m, double J) {
  double Mt;
  if (m.model == XModel::HyperelasticKG)
    Mt = 0.5 * m.kg.K * (J + 1.0 / J) + 4.0 / 3.0 * m.kg.G / (J * std::cbrt(J * J));
  else
    Mt = m.lame.lambda + 2.0 * m.lame.mu;
  if (Mt < 0) Mt = 0;
  return std::sqrt(Mt * J / m.density);
}

template <int dim>
KOKKOS_INLINE_FUNCTION Mat<dim> getF(const XParticles<dim>& p, LO q) {
  Mat<dim> F;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) F(i, j) = p.F(q, i, j);
  return F;
}

// The contact settings every kernel needs, by value.
struct ContactConfig {
  XNormals normals;
  XSeparation separation;
  double cp_delta_dx;  // delta_c * dx (m)
  LRSettings lr;
  int M;
};

// The classes that see a node: m^alpha > 1e-12 of the node's total mass
// (weights of round-off size at the edge of a support do not make a contact
// node). Returns their count, the classes in `present` (ascending).
KOKKOS_INLINE_FUNCTION int present_classes(const Kokkos::View<double*, MemSpace>& gm, LO node, int M, int* present) {
  double tot = 0;
  for (int a = 0; a < M; ++a) tot += gm(node * M + a);
  int n = 0;
  for (int a = 0; a < M; ++a)
    if (gm(node * M + a) > 1e-12 * tot) present[n++] = a;
  return n;
}

}  // namespace

template <int dim>
struct ExplicitSimulation<dim>::Impl {
  ExplicitSetup<dim> setup;
  XParticles<dim> p;
  GridSpec<dim> g;
  int M = 0;
  LO nn = 0;
  double time = 0;
  long step = 0;
  long over_limit = 0;
  // max_p (c_p + |v_p|) of the current state when known (>= 0): the step's
  // closing reduction computes it with the diagnostics, so the next step's
  // CFL limit needs no pass of its own; -1 after construction and restore.
  double known_cmax = -1;
  Kokkos::View<XMaterial*, MemSpace> mats;
  Kokkos::View<LawParams*, MemSpace> laws;
  Kokkos::View<LevelSet*, MemSpace> lsets;
  CellBins bins;
  // the particles' stencils of the step (both shapes use the 3-per-axis tensor stencil)
  Kokkos::View<TensorStencil<dim, 3>*, MemSpace> stencils;
  // grid fields (slot = node * M + a)
  DView gm, p0, pc, v, v0, dv, f, vp, grad, xm, vstar, normal, sep, zero;
  Scatter s_m, s_p, s_g, s_x, s_f;
  GridConstraints bc;
  Kokkos::View<LO*, MemSpace> cnodes;
  Kokkos::View<int*, MemSpace> lr_iters;
  XpicScratch xpic;

  explicit Impl(ExplicitSetup<dim> s) : setup(std::move(s)) {
    g = setup.grid;
    M = static_cast<int>(setup.materials.size());
    if (M < 1 || M > kMaxClasses)
      throw std::invalid_argument("explicit MPM: " + std::to_string(M) + " material classes; expected 1.." +
                                  std::to_string(kMaxClasses));
    nn = g.num_nodes();
    const auto& P = setup.particles;
    const std::size_t np = P.size();
    p.x = P.x;
    p.v = P.v;
    p.mass = P.mass;
    p.volume0 = P.volume0;
    p.F = P.F;
    p.cls = P.material;
    p.body = P.body;
    p.lp = DView("xmpm_lp", np);
    p.sigma = decltype(p.sigma)("xmpm_sigma", np);
    auto lp = p.lp;
    auto V0 = p.volume0;
    Kokkos::parallel_for(
        "xmpm_lp", Kokkos::RangePolicy<ExecSpace>(0, np),
        KOKKOS_LAMBDA(const LO q) { lp(q) = 0.5 * std::pow(V0(q), 1.0 / dim); });
    mats = Kokkos::View<XMaterial*, MemSpace>("xmpm_materials", M);
    auto hm = Kokkos::create_mirror_view(mats);
    for (int a = 0; a < M; ++a) hm(a) = setup.materials[a];
    Kokkos::deep_copy(mats, hm);
    laws = Kokkos::View<LawParams*, MemSpace>("xmpm_laws", M * M);
    auto hl = Kokkos::create_mirror_view(laws);
    for (int a = 0; a < M * M; ++a) hl(a) = setup.laws.empty() ? LawParams{ContactLaw::Coulomb, 0.0} : setup.laws[a];
    Kokkos::deep_copy(laws, hl);
    lsets = Kokkos::View<LevelSet*, MemSpace>("xmpm_level_sets", setup.level_sets.size());
    auto hs = Kokkos::create_mirror_view(lsets);
    for (std::size_t k = 0; k < setup.level_sets.size(); ++k) hs(k) = setup.level_sets[k];
    Kokkos::deep_copy(lsets, hs);

    const std::size_t ns = static_cast<std::size_t>(nn) * M;
    gm = DView("xmpm_mass", ns);
    p0 = DView("xmpm_p0", ns * dim);
    pc = DView("xmpm_p", ns * dim);
    v = DView("xmpm_v", ns * dim);
    v0 = DView("xmpm_v0", ns * dim);
    dv = DView("xmpm_dv", ns * dim);
    f = DView("xmpm_f", ns * dim);
    vp = DView("xmpm_vplus", ns * dim);
    vstar = DView("xmpm_vstar", ns * dim);
    normal = DView("xmpm_normal", ns * dim);
    sep = DView("xmpm_sep", ns);
    zero = DView("xmpm_zero", ns * dim);
    s_m = Scatter(gm);
    s_p = Scatter(p0);
    s_f = Scatter(f);
    if (setup.normals == XNormals::AG) {
      grad = DView("xmpm_grad", ns * dim);
      s_g = Scatter(grad);
      if (setup.separation == XSeparation::CP) {
        xm = DView("xmpm_xm", ns * dim);
        s_x = Scatter(xm);
      }
    }
    bc.flag = Kokkos::View<unsigned char*, MemSpace>("xmpm_bc_flag", static_cast<std::size_t>(nn) * dim);
    bc.value = DView("xmpm_bc_value", static_cast<std::size_t>(nn) * dim);
    cnodes = Kokkos::View<LO*, MemSpace>("xmpm_contact_nodes", nn);
    lr_iters = Kokkos::View<int*, MemSpace>("xmpm_lr_iters", nn);
    check_inside("at the start");
    update_stress_only();
  }

  void check_inside(const std::string& when) const {
    const auto pp = p;
    const auto gg = g;
    const bool gimp = setup.shape == XShape::UGimp;
    LO bad = -1;
    Kokkos::parallel_reduce(
        "xmpm_inside", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
        KOKKOS_LAMBDA(const LO q, LO& acc) {
          const Vec<dim> x = pos(pp, q);
          const bool in = gimp ? UGimp::contains<dim>(gg, x, pp.lp(q)) : QuadraticBSpline::contains<dim>(gg, x, pp.lp(q));
          if (!in && q > acc) acc = q;
        },
        Kokkos::Max<LO>(bad));
    if (bad >= 0) throw_outside(bad, when);
  }

  // The message of check_inside for particle `bad`.
  [[noreturn]] void throw_outside(LO bad, const std::string& when) const {
    auto xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    std::ostringstream m;
    m << "explicit MPM: particle " << bad << " at (";
    for (int d = 0; d < dim; ++d) m << (d ? ", " : "") << xh(bad, d);
    m << ") " << when << " (step " << step
      << ") has a shape-function stencil outside the grid; enlarge MPM/domain min / domain max";
    if (when == "at the start") throw std::invalid_argument(m.str());
    throw std::runtime_error(m.str());
  }

  // sigma from the current F (the initial state, for the first report).
  void update_stress_only() {
    const auto pp = p;
    const auto mt = mats;
    Kokkos::parallel_for(
        "xmpm_stress0", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          const Mat<dim> s = x_cauchy<dim>(mt(pp.cls(q)), getF(pp, q));
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j) pp.sigma(q, i, j) = s(i, j);
        });
    Kokkos::fence();
  }

  double dt_limit() const {
    if (known_cmax >= 0) return setup.cfl * g.dx / known_cmax;
    const auto pp = p;
    const auto mt = mats;
    double cmax = 0;
    Kokkos::parallel_reduce(
        "xmpm_cfl", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
        KOKKOS_LAMBDA(const LO q, double& acc) {
          const double J = getF(pp, q).determinant();
          double v2 = 0;
          for (int d = 0; d < dim; ++d) v2 += pp.v(q, d) * pp.v(q, d);
          const double c = x_wave_speed(mt(pp.cls(q)), J) + std::sqrt(v2);
          if (c > acc) acc = c;
        },
        Kokkos::Max<double>(cmax));
    return setup.cfl * g.dx / cmax;
  }

  void build_constraints(double t) {
    auto flag = bc.flag;
    auto val = bc.value;
    const auto ls = lsets;
    const int nls = static_cast<int>(lsets.extent(0));
    const auto gg = g;
    small_for(
        "xmpm_constraints", nn, KOKKOS_LAMBDA(const LO n) {
          for (int c = 0; c < dim; ++c) {
            flag(n * dim + c) = 0;
            val(n * dim + c) = 0;
          }
          const Vec<dim> xi = gg.node_position(n);
          for (int k = 0; k < nls; ++k) {
            const LevelSet& s = ls(k);
            if (s.template phi<dim>(xi, t) > 0) continue;
            if (s.slip) {  // axis-aligned normal (checked by the scene): that component only
              int ax = 0;
              for (int c = 1; c < dim; ++c)
                if (std::fabs(s.normal[c]) > std::fabs(s.normal[ax])) ax = c;
              flag(n * dim + ax) = 1;
              val(n * dim + ax) = s.velocity[ax];
            } else {
              for (int c = 0; c < dim; ++c) {
                flag(n * dim + c) = 1;
                val(n * dim + c) = s.velocity[c];
              }
            }
          }
        });
  }

  // v = mom / m at every slot; constrained components set to their value.
  void velocities(DView mom, DView out, bool constrain) const {
    const auto m = gm;
    const auto flag = bc.flag;
    const auto val = bc.value;
    const int MM = M;
    small_for(
        "xmpm_velocity", nn * M, KOKKOS_LAMBDA(const LO s) {
          const LO n = s / MM;
          for (int c = 0; c < dim; ++c) {
            double x = m(s) > 0 ? mom(s * dim + c) / m(s) : 0.0;
            if (constrain && flag(n * dim + c)) x = val(n * dim + c);
            out(s * dim + c) = x;
          }
        });
  }

  // Momenta at constrained components: m v_bc.
  void constrain_momenta(DView mom) const {
    const auto m = gm;
    const auto flag = bc.flag;
    const auto val = bc.value;
    const int MM = M;
    small_for(
        "xmpm_constrain", nn * M, KOKKOS_LAMBDA(const LO s) {
          const LO n = s / MM;
          for (int c = 0; c < dim; ++c)
            if (flag(n * dim + c)) mom(s * dim + c) = m(s) * val(n * dim + c);
        });
  }
};

namespace {

// The per-shape kernels of one step.
template <int dim, class Shape>
struct StepKernels {
  using St = typename Shape::template Stencil<dim>;
  using Impl = typename ExplicitSimulation<dim>::Impl;
  static_assert(std::is_same_v<St, TensorStencil<dim, 3>>, "Impl::stencils holds 3-per-axis tensor stencils");

  static void p2g(Impl& s) {
    const auto p = s.p;
    const auto g = s.g;
    const int M = s.M;
    const bool ag = s.setup.normals == XNormals::AG;
    const bool cp = ag && s.setup.separation == XSeparation::CP;
    s.s_m.reset();
    s.s_p.reset();
    auto sm = s.s_m, sp = s.s_p, sg = s.s_g, sx = s.s_x;
    if (ag) {
      s.s_g.reset();
    }
    if (cp) {
      s.s_x.reset();
    }
    if (s.stencils.extent(0) != p.size())
      s.stencils = decltype(s.stencils)(Kokkos::view_alloc("xmpm_stencils", Kokkos::WithoutInitializing), p.size());
    const auto sts = s.stencils;
    Kokkos::parallel_for(
        "xmpm_p2g", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          const Vec<dim> x = pos(p, q);
          const St st = Shape::template stencil<dim>(g, x, p.lp(q));
          sts(q) = st;  // the step's stencil (what compute_stencils stores), read by every later kernel
          const int a = p.cls(q);
          const double mq = p.mass(q);
          auto am = sm.access();
          auto ap = sp.access();
          for (int k = 0; k < St::size; ++k) {
            const double w = st.weight(k);
            if (w == 0.0) continue;
            const LO slot = st.node(g, k) * M + a;
            am(slot) += w * mq;
            for (int c = 0; c < dim; ++c) ap(slot * dim + c) += w * mq * p.v(q, c);
          }
          if (ag) {
            auto agr = sg.access();
            const double V = getF(p, q).determinant() * p.volume0(q);
            for (int k = 0; k < St::size; ++k) {
              const Vec<dim> G = st.gradient(k);
              const LO slot = st.node(g, k) * M + a;
              for (int c = 0; c < dim; ++c) agr(slot * dim + c) += G(c) * V;
            }
            if (cp) {
              auto ax = sx.access();
              for (int k = 0; k < St::size; ++k) {
                const double w = st.weight(k);
                const LO slot = st.node(g, k) * M + a;
                for (int c = 0; c < dim; ++c) ax(slot * dim + c) += w * mq * x(c);
              }
            }
          }
        });
    s.s_m.contribute();
    s.s_p.contribute();
    if (ag) s.s_g.contribute();
    if (cp) s.s_x.contribute();
  }

  // Contact nodes (>= 2 classes) into s.cnodes; returns (count, 3+ count).
  static std::pair<LO, LO> find_contact_nodes(Impl& s) {
    const auto gm = s.gm;
    const int M = s.M;
    auto list = s.cnodes;
    LO count = 0, multi = 0;
    if (M < 2) return {0, 0};
    small_scan(
        "xmpm_contact_nodes", s.nn,
        KOKKOS_LAMBDA(const LO n, LO& off, const bool final) {
          int present[ExplicitSimulation<dim>::kMaxClasses];
          const int k = present_classes(gm, n, M, present);
          if (k >= 2) {
            if (final) list(off) = n;
            ++off;
          }
        },
        count);
    small_reduce(
        "xmpm_multi_nodes", count,
        KOKKOS_LAMBDA(const LO i, LO& acc) {
          int present[ExplicitSimulation<dim>::kMaxClasses];
          acc += present_classes(gm, list(i), M, present) >= 3;
        },
        multi);
    return {count, multi};
  }

  // Normal (alpha -> the rest) and separation for each class alpha at each
  // contact node: at 2-class nodes only for the lower class (the pair's alpha).
  static void normals(Impl& s, LO count) {
    const auto p = s.p;
    const auto g = s.g;
    const auto bins = s.bins;
    const auto gm = s.gm, grad = s.grad, xm = s.xm;
    auto nrm = s.normal;
    auto sep = s.sep;
    auto iters = s.lr_iters;
    const auto list = s.cnodes;
    const ContactConfig cfg{s.setup.normals, s.setup.separation, s.setup.cp_delta * s.g.dx, s.setup.lr, s.M};
    // a few tens of nodes with unequal clouds and LR iteration counts: handed out one at a time
    Kokkos::parallel_for(
        "xmpm_normals", Kokkos::RangePolicy<ExecSpace, Kokkos::Schedule<Kokkos::Dynamic>>(0, count).set_chunk_size(1),
        KOKKOS_LAMBDA(const LO i) {
          const LO node = list(i);
          const int M = cfg.M;
          int present[ExplicitSimulation<dim>::kMaxClasses];
          const int np = present_classes(gm, node, M, present);
          const int nalpha = np == 2 ? 1 : np;
          const GridIndex<dim> I = g.node_multi_index(node);
          const Vec<dim> xi = g.node_position(node);
          int it_sum = 0;
          for (int ia = 0; ia < nalpha; ++ia) {
            const int a = present[ia];
            const LO slot = node * M + a;
            Vec<dim> n = Vec<dim>::Zero();
            double d = -1.0;
            if (cfg.normals == XNormals::LR) {
              // the point cloud: particles of the cells around the node that see it
              auto cloud = [&](auto&& visit) {
                int lo[dim], hi[dim];
                for (int e = 0; e < dim; ++e) {
                  lo[e] = I[e] - 2 < 0 ? 0 : I[e] - 2;
                  hi[e] = I[e] + 1 > g.n_cells[e] - 1 ? g.n_cells[e] - 1 : I[e] + 1;
                }
                int c[dim];
                for (int e = 0; e < dim; ++e) c[e] = lo[e];
                while (true) {
                  LO cell = 0;
                  for (int e = dim - 1; e >= 0; --e) cell = cell * g.n_cells[e] + c[e];
                  for (LO k = bins.start(cell); k < bins.start(cell + 1); ++k) {
                    const LO q = bins.sorted(k);
                    const Vec<dim> r = pos(p, q) - xi;
                    double w = 1.0;
                    for (int e = 0; e < dim; ++e) w *= Shape::node_weight_1d(r(e), g.dx, p.lp(q));
                    if (w > 1e-12) visit(q, r);  // round-off weights at the support edge are not in the cloud
                  }
                  int e = 0;
                  while (e < dim && ++c[e] > hi[e]) {
                    c[e] = lo[e];
                    ++e;
                  }
                  if (e == dim) break;
                }
              };
              const LRResult<dim> r = lr_fit<dim>(
                  [&](auto&& gfun) { cloud([&](LO q, const Vec<dim>& X) { gfun(X, p.cls(q) == a ? -1.0 : 1.0); }); },
                  g.dx, cfg.lr);
              it_sum += r.iterations;
              n = r.normal;
              double amax = -1e300, bmin = 1e300;
              cloud([&](LO q, const Vec<dim>& X) {
                Vec<dim> R0;
                for (int e = 0; e < dim; ++e) R0(e) = p.lp(q);
                const double R = ellipsoid_radius<dim>(getF(p, q), R0, n);
                const double xn = X.dot(n);
                if (p.cls(q) == a) {
                  if (xn + R > amax) amax = xn + R;
                } else if (xn - R < bmin) {
                  bmin = xn - R;
                }
              });
              d = bmin - amax - cfg.lr.contact_tolerance * g.dx;
            } else {
              Vec<dim> ga = Vec<dim>::Zero(), gb = Vec<dim>::Zero(), xa = Vec<dim>::Zero(), xb = Vec<dim>::Zero();
              double ma = 0, mb = 0;
              for (int b = 0; b < M; ++b) {
                const LO sb = node * M + b;
                for (int c = 0; c < dim; ++c) {
                  if (b == a) ga(c) += grad(sb * dim + c);
                  else gb(c) += grad(sb * dim + c);
                }
                if (cfg.separation == XSeparation::CP) {
                  for (int c = 0; c < dim; ++c) {
                    if (b == a) xa(c) += xm(sb * dim + c);
                    else xb(c) += xm(sb * dim + c);
                  }
                  if (b == a) ma += gm(sb);
                  else mb += gm(sb);
                }
              }
              n = ga - gb;
              const double len = n.norm();
              if (len > 0) n /= len;
              if (cfg.separation == XSeparation::CP) d = (xb / mb - xa / ma).dot(n) - cfg.cp_delta_dx;
            }
            for (int c = 0; c < dim; ++c) nrm(slot * dim + c) = n(c);
            sep(slot) = d;
          }
          iters(i) = cfg.normals == XNormals::LR ? it_sum : 0;
        });
  }

  // One contact pass on the momenta `mom` (in place); `dvout` (if given)
  // receives Delta p / m. Returns the nodes where a law acted.
  static LO pass(Impl& s, LO count, DView mom, DView dvout) {
    const auto gm = s.gm;
    const auto nrm = s.normal;
    const auto sep = s.sep;
    const auto laws = s.laws;
    const auto list = s.cnodes;
    const int M = s.M;
    const bool store = dvout.extent(0) > 0;
    if (store) small_fill(dvout, 0.0);
    LO active = 0;
    small_reduce(
        "xmpm_contact_pass", count,
        KOKKOS_LAMBDA(const LO i, LO& acc) {
          const LO node = list(i);
          int present[ExplicitSimulation<dim>::kMaxClasses];
          const int np = present_classes(gm, node, M, present);
          auto P = [&](int a) {
            Vec<dim> x;
            for (int c = 0; c < dim; ++c) x(c) = mom((node * M + a) * dim + c);
            return x;
          };
          auto N = [&](int a) {
            Vec<dim> x;
            for (int c = 0; c < dim; ++c) x(c) = nrm((node * M + a) * dim + c);
            return x;
          };
          bool any = false;
          if (np == 2) {
            const int a = present[0], b = present[1];
            const LawParams law = laws(a * M + b);
            const double ma = gm(node * M + a), mb = gm(node * M + b);
            bool act = false;
            Vec<dim> dp = Vec<dim>::Zero();
            if (law.law == ContactLaw::Stick || sep(node * M + a) < 0.0)
              dp = contact_momentum_change<dim>(law, ma, P(a), mb, P(b), N(a), act);
            if (act) {
              any = true;
              for (int c = 0; c < dim; ++c) {
                mom((node * M + a) * dim + c) += dp(c);
                mom((node * M + b) * dim + c) -= dp(c);
                if (store) {
                  dvout((node * M + a) * dim + c) = dp(c) / ma;
                  dvout((node * M + b) * dim + c) = -dp(c) / mb;
                }
              }
            }
          } else {
            // 3+ classes: each alpha against the lump of the others (Eq. 50),
            // all changes from the momenta before this pass.
            Vec<dim> dps[ExplicitSimulation<dim>::kMaxClasses];
            Vec<dim> ptot = Vec<dim>::Zero();
            double mtot = 0;
            for (int k = 0; k < np; ++k) {
              ptot += P(present[k]);
              mtot += gm(node * M + present[k]);
            }
            for (int k = 0; k < np; ++k) {
              const int a = present[k];
              const double ma = gm(node * M + a);
              int big = -1;
              double bigm = -1;
              for (int l = 0; l < np; ++l)
                if (l != k && gm(node * M + present[l]) > bigm) {
                  bigm = gm(node * M + present[l]);
                  big = present[l];
                }
              const LawParams law = laws(a * M + big);
              bool act = false;
              dps[k] = Vec<dim>::Zero();
              if (law.law == ContactLaw::Stick || sep(node * M + a) < 0.0)
                dps[k] = contact_momentum_change<dim>(law, ma, P(a), mtot - ma, ptot - P(a), N(a), act);
              any = any || act;
            }
            for (int k = 0; k < np; ++k) {
              const int a = present[k];
              for (int c = 0; c < dim; ++c) {
                mom((node * M + a) * dim + c) += dps[k](c);
                if (store) dvout((node * M + a) * dim + c) = dps[k](c) / gm(node * M + a);
              }
            }
          }
          acc += any;
        },
        active);
    return active;
  }

  // F <- (I + dt L) F with L = sum_i v_i^alpha (x) G_pi (Eq. 28) from the grid velocities `v`
  // (v^alpha before the momentum update, v^{alpha+} after it); sigma from F.
  static void stress_update(Impl& s, double dt, DView v) {
    const auto p = s.p;
    const auto g = s.g;
    const auto mt = s.mats;
    const int M = s.M;
    const auto sts = s.stencils;
    Kokkos::parallel_for(
        "xmpm_stress", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          const St& st = sts(q);
          const int a = p.cls(q);
          Mat<dim> L = Mat<dim>::Zero();
          for (int k = 0; k < St::size; ++k) {
            const Vec<dim> G = st.gradient(k);
            const LO slot = st.node(g, k) * M + a;
            for (int i = 0; i < dim; ++i)
              for (int j = 0; j < dim; ++j) L(i, j) += v(slot * dim + i) * G(j);
          }
          const Mat<dim> F = (Mat<dim>::Identity() + dt * L) * getF(p, q);
          const Mat<dim> sig = x_cauchy<dim>(mt(a), F);
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j) {
              p.F(q, i, j) = F(i, j);
              p.sigma(q, i, j) = sig(i, j);
            }
        });
  }

  static void forces(Impl& s) {
    const auto p = s.p;
    const auto g = s.g;
    const int M = s.M;
    double grav[3] = {s.setup.gravity[0], s.setup.gravity[1], s.setup.gravity[2]};
    const Vec<dim> gv = [&] {
      Vec<dim> x;
      for (int d = 0; d < dim; ++d) x(d) = grav[d];
      return x;
    }();
    s.s_f.reset();
    auto sf = s.s_f;
    const auto sts = s.stencils;
    Kokkos::parallel_for(
        "xmpm_forces", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          const St& st = sts(q);
          const int a = p.cls(q);
          const double V = getF(p, q).determinant() * p.volume0(q);
          Mat<dim> sig;
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j) sig(i, j) = p.sigma(q, i, j);
          auto af = sf.access();
          for (int k = 0; k < St::size; ++k) {
            const Vec<dim> fi = -V * (sig * st.gradient(k)) + (st.weight(k) * p.mass(q)) * gv;
            const LO slot = st.node(g, k) * M + a;
            for (int c = 0; c < dim; ++c) af(slot * dim + c) += fi(c);
          }
        });
    s.s_f.contribute();
  }

  static void provisional(Impl& s, double dt) {
    const auto gm = s.gm;
    const auto v = s.v, f = s.f;
    auto mom = s.vp;
    const int M = s.M;
    small_for(
        "xmpm_provisional", s.nn * M, KOKKOS_LAMBDA(const LO sl) {
          for (int c = 0; c < dim; ++c) mom(sl * dim + c) = gm(sl) * v(sl * dim + c) + f(sl * dim + c) * dt;
        });
  }

  static void g2p(Impl& s, double dt) {
    const auto p = s.p;
    const auto g = s.g;
    const int M = s.M;
    const auto v = s.v, vp = s.vp;
    const XUpdate up = s.setup.update;
    const int m = s.setup.xpic_order;
    const bool xpic = up == XUpdate::XPIC;
    DView v1 = s.v, dv1 = s.dv;
    if (xpic && !s.setup.xpic_corrected) {
      v1 = s.v0;
      dv1 = s.zero;
    }
    if (xpic)
      xpic_vstar<dim, Shape>(g, M, p, s.stencils, s.gm, v1, dv1, m, s.bc, s.vstar, s.xpic);
    const auto vs = s.vstar;
    const auto vone = v1;
    const auto sts = s.stencils;
    Kokkos::parallel_for(
        "xmpm_g2p", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          const St& st = sts(q);
          const int a = p.cls(q);
          double Svp[dim] = {}, Sa[dim] = {}, Sv1[dim] = {}, Svs[dim] = {};
          for (int k = 0; k < St::size; ++k) {
            const double w = st.weight(k);
            if (w == 0.0) continue;
            const LO sl = (st.node(g, k) * M + a) * dim;
            for (int c = 0; c < dim; ++c) {
              Svp[c] += w * vp(sl + c);
              Sa[c] += w * (vp(sl + c) - v(sl + c)) / dt;
              if (xpic) {
                Sv1[c] += w * vone(sl + c);
                Svs[c] += w * vs(sl + c);
              }
            }
          }
          for (int c = 0; c < dim; ++c) {
            if (up == XUpdate::FLIP) {
              p.v(q, c) += dt * Sa[c];
              p.x(q, c) += dt * Svp[c];
            } else {
              p.v(q, c) = up == XUpdate::PIC ? Svp[c] : m * (Sv1[c] - Svs[c]) + dt * Sa[c];
              // PIC / XPIC positions: X += dt S (v^alpha + dt/2 a^alpha) = dt (S v^{alpha+} - dt/2 S a^alpha),
              // the lumped (contact-corrected) grid velocity that also drives F (steps 4, 6), averaged over
              // the step. Not the XPIC particle velocity: X += dt (V^{n+1} - dt/2 S a) moves the particles
              // with m S (v - v*), a sharpened field (mode factor (1 - (1 - lambda)^m) / lambda of
              // S^{+alpha} S) that F never sees; positions and F then drift apart and single-material
              // XPIC(5) in B1(b) grew an axial standing wave until it blew up at 16.6 % strain (dt 0.9).
              p.x(q, c) += dt * (Svp[c] - 0.5 * dt * Sa[c]);
            }
          }
        });
  }

  static ExplicitReport step(Impl& s) {
    Kokkos::Timer total, t;
    ExplicitReport r;
    const double limit = s.dt_limit();
    double dt = s.setup.fixed_dt > 0 ? s.setup.fixed_dt : limit;
    if (s.setup.fixed_dt > 0 && dt > limit) s.over_limit++;
    r.dt_limit = limit;
    s.known_cmax = -1;  // the particles move in this step
    bin_particles(s.g, s.p, s.bins);
    s.build_constraints(s.time);
    p2g(s);
    Kokkos::fence();
    r.p2g_s += t.seconds();
    t.reset();
    const auto [count, multi] = find_contact_nodes(s);
    r.contact_nodes = count;
    r.multi_nodes = multi;
    if (count > 0) normals(s, count);
    small_copy(s.pc, s.p0);
    if (count > 0 && s.setup.contact_passes == 2) pass(s, count, s.pc, s.dv);
    else small_fill(s.dv, 0.0);
    Kokkos::fence();
    r.contact_s += t.seconds();
    t.reset();
    s.velocities(s.pc, s.v, true);
    s.velocities(s.p0, s.v0, true);
    const XStrainUpdate su = s.setup.strain_update;
    if (su == XStrainUpdate::USF) stress_update(s, dt, s.v);
    else if (su == XStrainUpdate::USAVG) stress_update(s, 0.5 * dt, s.v);
    Kokkos::fence();
    r.stress_s += t.seconds();
    t.reset();
    forces(s);
    provisional(s, dt);
    s.constrain_momenta(s.vp);
    Kokkos::fence();
    r.p2g_s += t.seconds();
    t.reset();
    if (count > 0) r.active_nodes = pass(s, count, s.vp, DView());
    Kokkos::fence();
    r.contact_s += t.seconds();
    t.reset();
    s.velocities(s.vp, s.vp, true);
    if (su != XStrainUpdate::USF) {
      // USL / USAVG: (the rest of) the increment from v^{alpha+}, at the positions of this step's P2G
      stress_update(s, su == XStrainUpdate::USL ? dt : 0.5 * dt, s.vp);
      Kokkos::fence();
      r.stress_s += t.seconds();
      t.reset();
    }
    g2p(s, dt);
    Kokkos::fence();
    r.g2p_s += t.seconds();
    if (count > 0 && s.setup.normals == XNormals::LR) {
      const auto it = s.lr_iters;
      int mx = 0;
      long sum = 0;
      small_reduce(
          "xmpm_lr_stats", count,
          KOKKOS_LAMBDA(const LO i, long& a) { a += it(i); }, sum);
      small_reduce(
          "xmpm_lr_max", count,
          KOKKOS_LAMBDA(const LO i, int& a) {
            if (it(i) > a) a = it(i);
          },
          Kokkos::Max<int>(mx));
      r.lr_iter_mean = double(sum) / count;
      r.lr_iter_max = mx;
    }
    s.time += dt;
    s.step++;
    r.dt = dt;
    r.step_s = total.seconds();
    return r;
  }
};

template <int dim>
ExplicitReport step_dispatch(typename ExplicitSimulation<dim>::Impl& s) {
  if (s.setup.shape == XShape::UGimp) return StepKernels<dim, UGimp>::step(s);
  return StepKernels<dim, QuadraticBSpline>::step(s);
}

}  // namespace

template <int dim>
ExplicitSimulation<dim>::ExplicitSimulation(ExplicitSetup<dim> setup) : impl_(std::make_unique<Impl>(std::move(setup))) {
  const double limit = impl_->dt_limit();
  if (impl_->setup.fixed_dt > 0 && impl_->setup.fixed_dt > limit) {
    std::ostringstream m;
    m.precision(6);
    m << "scene key 'Time/dt' = " << impl_->setup.fixed_dt << ": expected <= the CFL limit " << limit
      << " s at t = 0 (Time/CFL " << impl_->setup.cfl << " x dx / max wave speed)";
    throw std::invalid_argument(m.str());
  }
}

template <int dim>
ExplicitSimulation<dim>::~ExplicitSimulation() = default;

// The step's closing reduction: the diagnostics, the containment check
// (check_inside) and the next step's CFL wave speed in one pass over the
// particles (reductions of the same partition, so the same sums as three).
template <int dim>
ExplicitReport ExplicitSimulation<dim>::step() {
  ExplicitReport r = step_dispatch<dim>(*impl_);
  double cmax = 0;
  LO bad = -1;
  const ExplicitReport d = reduce_state(&cmax, &bad);
  if (bad >= 0) impl_->throw_outside(bad, "after the step");
  impl_->known_cmax = cmax;
  r.step = impl_->step;
  r.time = impl_->time;
  r.momentum = d.momentum;
  r.kinetic = d.kinetic;
  r.stress_body = d.stress_body;
  r.stress_all = d.stress_all;
  return r;
}

namespace {
// Sums, except cmax and bad, which join by max (their identities 0 and -1).
struct XDiag {
  double m[3] = {0, 0, 0};
  double ke = 0, sb = 0, sa = 0;
  long nb = 0, na = 0;
  double cmax = -std::numeric_limits<double>::max();  // max_p (c_p + |v_p|), m/s (as Kokkos::Max's identity)
  LO bad = -1;      // largest index of a particle outside the grid
  KOKKOS_INLINE_FUNCTION XDiag& operator+=(const XDiag& o) {
    for (int i = 0; i < 3; ++i) m[i] += o.m[i];
    ke += o.ke;
    sb += o.sb;
    sa += o.sa;
    nb += o.nb;
    na += o.na;
    if (o.cmax > cmax) cmax = o.cmax;
    if (o.bad > bad) bad = o.bad;
    return *this;
  }
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile XDiag& o) volatile {
    for (int i = 0; i < 3; ++i) m[i] += o.m[i];
    ke += o.ke;
    sb += o.sb;
    sa += o.sa;
    nb += o.nb;
    na += o.na;
    if (o.cmax > cmax) cmax = o.cmax;
    if (o.bad > bad) bad = o.bad;
  }
};
}  // namespace
}  // namespace bfemp

namespace Kokkos {
template <>
struct reduction_identity<bfemp::XDiag> {
  KOKKOS_FORCEINLINE_FUNCTION static bfemp::XDiag sum() { return bfemp::XDiag(); }
};
}  // namespace Kokkos

namespace bfemp {

template <int dim>
ExplicitReport ExplicitSimulation<dim>::diagnostics() const {
  return reduce_state(nullptr, nullptr);
}

template <int dim>
ExplicitReport ExplicitSimulation<dim>::reduce_state(double* cmax, LO* bad) const {
  const bool closing = cmax != nullptr;
  const auto p = impl_->p;
  const int body = impl_->setup.stress_body;
  const int ax = impl_->setup.stress_axis;
  const auto gg = impl_->g;
  const auto mt = impl_->mats;
  const bool gimp = impl_->setup.shape == XShape::UGimp;
  XDiag d;
  Kokkos::parallel_reduce(
      closing ? "xmpm_close_step" : "xmpm_diagnostics", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
      KOKKOS_LAMBDA(const LO q, XDiag& a) {
        if (closing) {
          const Vec<dim> x = pos(p, q);
          const bool in = gimp ? UGimp::contains<dim>(gg, x, p.lp(q)) : QuadraticBSpline::contains<dim>(gg, x, p.lp(q));
          if (!in && q > a.bad) a.bad = q;
          double v2 = 0;
          for (int c = 0; c < dim; ++c) v2 += p.v(q, c) * p.v(q, c);
          const double cq = x_wave_speed(mt(p.cls(q)), getF(p, q).determinant()) + std::sqrt(v2);
          if (cq > a.cmax) a.cmax = cq;
        }
        double v2 = 0;
        for (int c = 0; c < dim; ++c) {
          a.m[c] += p.mass(q) * p.v(q, c);
          v2 += p.v(q, c) * p.v(q, c);
        }
        a.ke += 0.5 * p.mass(q) * v2;
        a.sa += p.sigma(q, ax, ax);
        a.na += 1;
        if (body < 0 || p.body(q) == body) {
          a.sb += p.sigma(q, ax, ax);
          a.nb += 1;
        }
      },
      Kokkos::Sum<XDiag>(d));
  if (closing) {
    *cmax = d.cmax;
    *bad = d.bad;
  }
  ExplicitReport r;
  r.step = impl_->step;
  r.time = impl_->time;
  for (int c = 0; c < 3; ++c) r.momentum[c] = d.m[c];
  r.kinetic = d.ke;
  r.stress_all = d.na ? d.sa / d.na : 0;
  r.stress_body = d.nb ? d.sb / d.nb : 0;
  return r;
}

template <int dim>
double ExplicitSimulation<dim>::time() const { return impl_->time; }
template <int dim>
long ExplicitSimulation<dim>::step_index() const { return impl_->step; }
template <int dim>
double ExplicitSimulation<dim>::dt_limit() const { return impl_->dt_limit(); }
template <int dim>
long ExplicitSimulation<dim>::steps_over_limit() const { return impl_->over_limit; }
template <int dim>
int ExplicitSimulation<dim>::num_classes() const { return impl_->M; }
template <int dim>
const ExplicitSetup<dim>& ExplicitSimulation<dim>::setup() const { return impl_->setup; }
template <int dim>
const xmpm::XParticles<dim>& ExplicitSimulation<dim>::particles() const { return impl_->p; }
template <int dim>
const GridSpec<dim>& ExplicitSimulation<dim>::grid() const { return impl_->g; }

template <int dim>
ExplicitState ExplicitSimulation<dim>::state() const {
  const auto& p = impl_->p;
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.F);
  ExplicitState s;
  s.time = impl_->time;
  s.step = impl_->step;
  s.over_limit = impl_->over_limit;
  s.x.assign(x.data(), x.data() + x.size());
  s.v.assign(v.data(), v.data() + v.size());
  s.F.assign(F.data(), F.data() + F.size());
  return s;
}

template <int dim>
void ExplicitSimulation<dim>::restore(const ExplicitState& s) {
  auto& p = impl_->p;
  const std::size_t np = p.size();
  auto check = [&](const std::vector<double>& a, std::size_t per, const char* name) {
    if (a.size() != np * per)
      throw std::invalid_argument(std::string("restart: explicit state '") + name + "' holds " +
                                  std::to_string(a.size()) + " values; expected " + std::to_string(np * per) + " (" +
                                  std::to_string(np) + " particles)");
  };
  check(s.x, dim, "particle_x");
  check(s.v, dim, "particle_v");
  check(s.F, dim * dim, "particle_F");
  auto x = Kokkos::create_mirror_view(p.x);
  auto v = Kokkos::create_mirror_view(p.v);
  auto F = Kokkos::create_mirror_view(p.F);
  std::copy(s.x.begin(), s.x.end(), x.data());
  std::copy(s.v.begin(), s.v.end(), v.data());
  std::copy(s.F.begin(), s.F.end(), F.data());
  Kokkos::deep_copy(p.x, x);
  Kokkos::deep_copy(p.v, v);
  Kokkos::deep_copy(p.F, F);
  impl_->time = s.time;
  impl_->step = s.step;
  impl_->over_limit = s.over_limit;
  impl_->known_cmax = -1;
  impl_->update_stress_only();
  impl_->check_inside("at the restart");
}

template class ExplicitSimulation<2>;
template class ExplicitSimulation<3>;

}  // namespace bfemp
