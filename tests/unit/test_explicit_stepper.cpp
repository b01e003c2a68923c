// Small checks of the explicit multimaterial stepper (paper 001 §3.2, §3.4):
//  - 3D: two blocks colliding frictionlessly (LR normals, two passes, FLIP):
//    the total momentum is conserved to round-off (each 2-class node changes
//    the pair's momenta by +dp and -dp, Eq. 7), and contact acts;
//  - 2D, three classes meeting at a node (3+ nodes handled by lumping, Eq. 50):
//    with the stick law the lumped changes dp^a = m^a p / m - p^a sum to zero,
//    so the total momentum is conserved to round-off although each class is
//    corrected alone; the run must see 3+ nodes.
//  - 2D, one class, random particle velocities, a very soft material (forces
//    negligible), one step: PIC / XPIC(5) particle velocities are P V with
//    P = I - (I - S S^+)^m (Eq. 36; m = 1: S S^+ V), and the positions move
//    with the lumped grid velocity S S^+ V (the field that updates F), not
//    with the XPIC particle velocity P V.
//  - 2D, one class, a pre-strained block at rest, one step with each strain
//    update (Explicit/strain update): USF strains from v^alpha = 0 (F
//    unchanged), USL from v^{alpha+} (dt L+), USAVG half of that; the forces,
//    hence particle velocities and positions, are the same in all three.
// No walls, no gravity; uGIMP, 2 particles per cell per axis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "explicit/explicit_simulation.hpp"
#include "kernels/explicit/shape_functions.hpp"
#include "mpm/sampling.hpp"

namespace {

using namespace bfemp;

template <int dim>
Particles<dim> block(const std::vector<double>& c, const std::vector<double>& size, double dx, int body,
                     const std::vector<double>& v) {
  SamplingShape sh;
  sh.kind = "box";
  sh.center = c;
  sh.size = size;
  Particles<dim> p = sample_particles<dim>(sh, dx, dim == 2 ? 4 : 8, 1000.0, body, body);  // 2 per cell per axis
  for (int d = 0; d < dim; ++d) Kokkos::deep_copy(Kokkos::subview(p.v, Kokkos::ALL(), d), v[d]);
  return p;
}

template <int dim>
ExplicitSetup<dim> base(int classes, double dx, int cells, xmpm::ContactLaw law) {
  ExplicitSetup<dim> s;
  s.grid.dx = dx;
  for (int d = 0; d < dim; ++d) {
    s.grid.origin[d] = -0.5 * cells * dx;
    s.grid.n_cells[d] = cells;
  }
  XMaterial m;
  m.model = XModel::HyperelasticKG;
  m.kg = {2450e6, 940e6};
  m.density = 1000.0;
  s.materials.assign(classes, m);
  for (int a = 0; a < classes; ++a) {
    s.class_names.push_back("c" + std::to_string(a));
    s.body_names.push_back("b" + std::to_string(a));
  }
  s.laws.assign(classes * classes, xmpm::LawParams{law, 0.0});
  s.update = XUpdate::FLIP;
  s.normals = XNormals::LR;
  return s;
}

template <int dim>
double total_mass(const Particles<dim>& p) {
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  double t = 0;
  for (std::size_t q = 0; q < m.extent(0); ++q) t += m(q);
  return t;
}

TEST(ExplicitStepper, FrictionlessCollision3DConservesMomentum) {
  const double dx = 0.005;
  ExplicitSetup<3> s = base<3>(2, dx, 16, xmpm::ContactLaw::Frictionless);
  // two 20 mm cubes 2.5 mm apart along z, offset in x and y (an oblique contact plane is not needed:
  // the offset exercises the edges), approaching at 2 x 5 m/s with a sideways component
  const Particles<3> a = block<3>({-0.002, 0.0, -0.01125}, {0.02, 0.02, 0.02}, dx, 0, {0.5, 0.2, 5.0});
  const Particles<3> b = block<3>({0.003, 0.0025, 0.01125}, {0.02, 0.02, 0.02}, dx, 1, {-0.3, 0.0, -5.0});
  s.particles = concatenate(std::vector<Particles<3>>{a, b});
  ExplicitSimulation<3> sim(s);
  const ExplicitReport r0 = sim.diagnostics();
  const double scale = total_mass(s.particles) * 5.0;
  long contact_steps = 0;
  double worst = 0;
  for (int n = 0; n < 300; ++n) {
    const ExplicitReport r = sim.step();
    contact_steps += r.active_nodes > 0;
    for (int c = 0; c < 3; ++c) worst = std::fmax(worst, std::fabs(r.momentum[c] - r0.momentum[c]) / scale);
  }
  std::printf("3D frictionless collision: %ld of 300 steps with contact, max |dP| / (M v) = %.3g\n", contact_steps,
              worst);
  EXPECT_GT(contact_steps, 10);
  EXPECT_LT(worst, 1e-13);
}

TEST(ExplicitStepper, ThreeClassesLumpedStickConservesMomentum) {
  const double dx = 0.005;
  ExplicitSetup<2> s = base<2>(3, dx, 24, xmpm::ContactLaw::Stick);
  // three blocks meeting near the origin: two below (left, right), one above, all moving toward the origin
  const Particles<2> a = block<2>({-0.01, -0.01}, {0.02, 0.02}, dx, 0, {2.0, 1.0});
  const Particles<2> b = block<2>({0.01, -0.01}, {0.02, 0.02}, dx, 1, {-1.5, 1.5});
  const Particles<2> c = block<2>({0.0, 0.01}, {0.04, 0.02}, dx, 2, {0.3, -2.5});
  s.particles = concatenate(std::vector<Particles<2>>{a, b, c});
  ExplicitSimulation<2> sim(s);
  const ExplicitReport r0 = sim.diagnostics();
  const double scale = total_mass(s.particles) * 2.5;
  long multi = 0;
  double worst = 0;
  for (int n = 0; n < 200; ++n) {
    const ExplicitReport r = sim.step();
    multi += r.multi_nodes;
    for (int c = 0; c < 2; ++c) worst = std::fmax(worst, std::fabs(r.momentum[c] - r0.momentum[c]) / scale);
  }
  std::printf("three classes, stick, lumped 3+ nodes: %ld node-steps with 3+ classes, max |dP| / (M v) = %.3g\n",
              multi, worst);
  EXPECT_GT(multi, 0);
  EXPECT_LT(worst, 1e-13);
}

TEST(ExplicitStepper, PicXpicPositionsMoveWithTheLumpedGridVelocity) {
  const double dx = 0.01, dt = 1e-5;
  for (const int m : {1, 5}) {
    ExplicitSetup<2> s = base<2>(1, dx, 12, xmpm::ContactLaw::Frictionless);
    s.materials[0].kg = {1.0, 1.0};  // Pa: stresses, forces and S a dt negligible (~1e-10 m/s)
    s.update = m == 1 ? XUpdate::PIC : XUpdate::XPIC;
    s.xpic_order = m;
    s.fixed_dt = dt;
    s.particles = block<2>({0.003, -0.002}, {0.04, 0.04}, dx, 0, {0.0, 0.0});
    const std::size_t np = s.particles.size();
    auto hv = Kokkos::create_mirror_view(s.particles.v);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (std::size_t q = 0; q < np; ++q)
      for (int c = 0; c < 2; ++c) hv(q, c) = u(rng);
    Kokkos::deep_copy(s.particles.v, hv);
    Kokkos::View<double* [2], Kokkos::HostSpace> x0("x0", np);  // a copy (a host mirror of a host View is the View)
    Kokkos::deep_copy(x0, s.particles.x);
    const auto hm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.particles.mass);
    ExplicitSimulation<2> sim(s);
    const auto lp = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().lp);
    const GridSpec<2> g = sim.grid();
    // S (uGIMP weights at the start positions) and the operator S S^+ on particle vectors
    std::vector<xmpm::UGimp::Stencil<2>> st(np);
    std::vector<double> gm(g.num_nodes(), 0.0);
    for (std::size_t q = 0; q < np; ++q) {
      st[q] = xmpm::UGimp::stencil<2>(g, Vec<2>(x0(q, 0), x0(q, 1)), lp(q));
      for (int k = 0; k < st[q].size; ++k) gm[st[q].node(g, k)] += st[q].weight(k) * hm(q);
    }
    auto SSp = [&](const std::vector<double>& W) {  // W: np x 2
      std::vector<double> gp(2 * gm.size(), 0.0), out(2 * np, 0.0);
      for (std::size_t q = 0; q < np; ++q)
        for (int k = 0; k < st[q].size; ++k)
          for (int c = 0; c < 2; ++c) gp[2 * st[q].node(g, k) + c] += st[q].weight(k) * hm(q) * W[2 * q + c];
      for (std::size_t q = 0; q < np; ++q)
        for (int k = 0; k < st[q].size; ++k) {
          const LO i = st[q].node(g, k);
          if (gm[i] > 0)
            for (int c = 0; c < 2; ++c) out[2 * q + c] += st[q].weight(k) * gp[2 * i + c] / gm[i];
        }
      return out;
    };
    std::vector<double> V(2 * np);
    for (std::size_t q = 0; q < np; ++q)
      for (int c = 0; c < 2; ++c) V[2 * q + c] = hv(q, c);
    const std::vector<double> U = SSp(V);  // S v: the lumped grid velocity at the particles
    std::vector<double> R = V;             // (I - S S^+)^m V
    for (int k = 0; k < m; ++k) {
      const std::vector<double> SR = SSp(R);
      for (std::size_t j = 0; j < R.size(); ++j) R[j] -= SR[j];
    }
    sim.step();
    const auto x1 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().x);
    const auto v1 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().v);
    double e_pos = 0, e_vel = 0, pv_vs_u = 0;
    for (std::size_t q = 0; q < np; ++q)
      for (int c = 0; c < 2; ++c) {
        const double PV = V[2 * q + c] - R[2 * q + c];
        e_pos = std::fmax(e_pos, std::fabs((x1(q, c) - x0(q, c)) / dt - U[2 * q + c]));
        e_vel = std::fmax(e_vel, std::fabs(v1(q, c) - PV));
        pv_vs_u = std::fmax(pv_vs_u, std::fabs(PV - U[2 * q + c]));
      }
    std::printf("m = %d: max |dX/dt - S S+ V| = %.3g, max |V1 - P V| = %.3g m/s (max |P V - S S+ V| = %.3g)\n", m, e_pos,
                e_vel, pv_vs_u);
    EXPECT_LT(e_pos, 1e-6) << "m = " << m;
    EXPECT_LT(e_vel, 1e-6) << "m = " << m;
    if (m > 1) EXPECT_GT(pv_vs_u, 1e-2);  // the check can tell the two position updates apart
  }
}

TEST(ExplicitStepper, StrainUpdateOrderingsFromRest) {
  const double dx = 0.01, dt = 1e-6;  // CFL limit 0.5 dx / c = 2.6e-6 s
  const double F0[2][2] = {{1.002, 0.001}, {0.0, 0.997}};
  struct Out {
    std::vector<double> F, x, v;
  };
  auto one_step = [&](XStrainUpdate su) {
    ExplicitSetup<2> s = base<2>(1, dx, 12, xmpm::ContactLaw::Frictionless);
    s.strain_update = su;
    s.fixed_dt = dt;
    s.particles = block<2>({0.003, -0.002}, {0.04, 0.04}, dx, 0, {0.0, 0.0});
    auto hF = Kokkos::create_mirror_view(s.particles.F);
    for (std::size_t q = 0; q < s.particles.size(); ++q)
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) hF(q, i, j) = F0[i][j];
    Kokkos::deep_copy(s.particles.F, hF);
    ExplicitSimulation<2> sim(s);
    sim.step();
    const auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().F);
    const auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().x);
    const auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().v);
    Out o;
    for (std::size_t q = 0; q < x.extent(0); ++q)
      for (int i = 0; i < 2; ++i) {
        o.x.push_back(x(q, i));
        o.v.push_back(v(q, i));
        for (int j = 0; j < 2; ++j) o.F.push_back(F(q, i, j));
      }
    return o;
  };
  const Out f = one_step(XStrainUpdate::USF), l = one_step(XStrainUpdate::USL), a = one_step(XStrainUpdate::USAVG);
  double usf_change = 0, dl_max = 0, avg_vs_half = 0, vmax = 0;
  for (std::size_t k = 0; k < f.F.size(); ++k) {
    const double f0 = F0[(k / 2) % 2][k % 2];
    usf_change = std::fmax(usf_change, std::fabs(f.F[k] - f0));
    dl_max = std::fmax(dl_max, std::fabs(l.F[k] - f0));
    avg_vs_half = std::fmax(avg_vs_half, std::fabs((a.F[k] - f0) - 0.5 * (l.F[k] - f0)));
  }
  for (double x : f.v) vmax = std::fmax(vmax, std::fabs(x));
  std::printf("pre-strained block at rest, one step: max |F - F0| USF %.3g, USL %.3g; max |dF_USAVG - dF_USL / 2| = %.3g; "
              "max |V| %.3g m/s\n",
              usf_change, dl_max, avg_vs_half, vmax);
  EXPECT_EQ(usf_change, 0.0);        // L from v^alpha = 0
  EXPECT_GT(dl_max, 1e-6);           // L+ from v^{alpha+} = f dt / m at the block's edges
  EXPECT_LT(avg_vs_half, 1e-9 * dl_max);
  EXPECT_GT(vmax, 0.01);
  EXPECT_EQ(f.v, l.v);  // the forces come from sigma(F0) in all three
  EXPECT_EQ(f.v, a.v);
  EXPECT_EQ(f.x, l.x);
  EXPECT_EQ(f.x, a.x);
}

// The CFL limit of the state after a step comes from the step's closing
// reduction (with the diagnostics and the containment check), not a pass of
// its own. It must be the limit of that state: CFL dx / max_p (c_p + |v_p|),
// c_p from Eq. 18's tangent P-wave modulus M_t = K/2 (J + 1/J) + 4/3 G J^(-5/3)
// (c = sqrt(M_t J / rho)), recomputed here on the host; a limit left over
// from the state before the step fails (the collision changes |v| and J by
// far more than the tolerance each step). After restore() it is the restored
// state's.
TEST(ExplicitStepper, CflLimitAfterAStepAndARestoreIsTheStatesOwn) {
  const double dx = 0.005;
  ExplicitSetup<2> s = base<2>(2, dx, 24, xmpm::ContactLaw::Frictionless);
  const Particles<2> a = block<2>({-0.011, 0.0}, {0.02, 0.02}, dx, 0, {20.0, 3.0});
  const Particles<2> b = block<2>({0.011, 0.001}, {0.02, 0.02}, dx, 1, {-20.0, 0.0});
  s.particles = concatenate(std::vector<Particles<2>>{a, b});
  ExplicitSimulation<2> sim(s);
  auto host_limit = [&] {
    const auto& p = sim.particles();
    auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
    auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.F);
    const double K = s.materials[0].kg.K, G = s.materials[0].kg.G, rho = s.materials[0].density;
    double cmax = 0;
    for (std::size_t q = 0; q < v.extent(0); ++q) {
      const double J = F(q, 0, 0) * F(q, 1, 1) - F(q, 0, 1) * F(q, 1, 0);
      const double Mt = 0.5 * K * (J + 1.0 / J) + 4.0 / 3.0 * G * std::pow(J, -5.0 / 3.0);
      cmax = std::fmax(cmax, std::sqrt(Mt * J / rho) + std::hypot(v(q, 0), v(q, 1)));
    }
    return s.cfl * dx / cmax;
  };
  EXPECT_NEAR(sim.dt_limit(), host_limit(), 1e-12 * host_limit());
  const ExplicitState early = sim.state();
  const double early_limit = host_limit();
  double prev = sim.dt_limit(), changed = 0;
  long contact_steps = 0;
  for (int n = 0; n < 60; ++n) {
    const ExplicitReport r = sim.step();
    contact_steps += r.active_nodes > 0;
    const double want = host_limit();
    ASSERT_NEAR(sim.dt_limit(), want, 1e-12 * want) << "after step " << n + 1;
    changed = std::fmax(changed, std::fabs(want - prev) / want);
    prev = want;
  }
  EXPECT_GT(contact_steps, 0);
  EXPECT_GT(changed, 1e-9);  // the limit moves by more than the tolerance: a stale one would fail
  sim.restore(early);
  EXPECT_NEAR(sim.dt_limit(), early_limit, 1e-12 * early_limit);
}

}  // namespace
