// The scene schema: every key with its default and documentation.
#include <Teuchos_Array.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>

#include "io/scene.hpp"
#include "io/scene_validate.hpp"
#include "solver/linear_solver.hpp"

namespace bfemp {

using Teuchos::Array;
using Teuchos::ParameterList;
using Teuchos::tuple;

namespace {

void choice(ParameterList& pl, const std::string& key, const std::string& def, const std::string& doc,
            const Teuchos::ArrayView<const std::string>& values) {
  pl.set(key, def, doc, Teuchos::rcp(new Teuchos::StringValidator(values)));
}

ParameterList material_schema() {
  ParameterList m("material");
  choice(m, "model", "neo-hookean",
         "constitutive model (paper Eq. 7, or small-strain linear; hyperelastic-kg: paper 001 Eq. 18 with K, G, "
         "explicit scenes only)",
         tuple<std::string>("neo-hookean", "linear", "hyperelastic-kg"));
  m.set("K", 0.0, "bulk modulus (Pa), > 0 (model hyperelastic-kg)");
  m.set("G", 0.0, "shear modulus (Pa), > 0 (model hyperelastic-kg)");
  m.set("E", 1e6, "Young's modulus (Pa), > 0");
  m.set("nu", 0.3, "Poisson ratio, in (-1, 0.5)");
  m.set("density", 1000.0, "rest density (kg/m^3; kg/m^2 in 2D), > 0");
  return m;
}

ParameterList segment_schema() {
  ParameterList s("segment");
  choice(s, "type", "fixed", "fixed, velocity (constant), or rotation (rigid, about axis through center)",
         tuple<std::string>("fixed", "velocity", "rotation"));
  s.set("duration", 1e300, "seconds this segment lasts; the next starts after it");
  s.set("velocity", Array<double>(), "m/s, dim components (type velocity)");
  s.set("angular velocity", 0.0, "rad/s about axis, right-handed (type rotation)");
  s.set("center", Array<double>(), "m, dim components: a point on the rotation axis");
  s.set("axis", Array<double>(), "rotation axis (3D; 2D rotates about z)");
  return s;
}

ParameterList bc_schema() {
  ParameterList b("boundary condition");
  b.set("node set", std::string(""), "named node set of the mesh (physical group or shape set)");
  b.set("box min", Array<double>(), "select nodes inside [box min, box max] (alternative to node set)");
  b.set("box max", Array<double>(), "upper corner of the selection box");
  b.sublist("Motion", false, "segments applied in order (any names; sorted by name)")
      .disableRecursiveValidation();
  return b;
}

ParameterList body_schema() {
  ParameterList b("FEM body");
  b.set("material", std::string(""), "name of an entry of Materials");
  b.set("initial velocity", Array<double>(), "m/s, dim components (default 0)");
  auto& mesh = b.sublist("Mesh", false, "a Gmsh MSH 4.1 file or a generated shape");
  mesh.set("file", std::string(""), "path to a .msh (v4 ASCII) file, relative to the scene file");
  choice(mesh, "shape", "none", "generated with the Gmsh API when no file is given",
         tuple<std::string>("none", "rectangle", "box", "disk", "ring", "half-ring", "spherical-shell"));
  mesh.set("center", Array<double>(), "m, dim components (default origin)");
  mesh.set("size", Array<double>(), "rectangle [w, h] or box [a, b, c] (m)");
  mesh.set("inner radius", 0.0, "m (ring, half-ring, spherical-shell)");
  mesh.set("outer radius", 0.0, "m (disk, ring, half-ring, spherical-shell)");
  mesh.set("element size", 0.0, "target edge length (m) for generated shapes");
  b.sublist("Boundary Conditions", false, "prescribed node sets, one sublist each")
      .disableRecursiveValidation();
  return b;
}

ParameterList mpm_body_schema() {
  ParameterList b("MPM body");
  b.set("material", std::string(""), "name of an entry of Materials");
  choice(b, "shape", "box", "region sampled with particles",
         tuple<std::string>("box", "disk", "sphere", "ring", "half-ring", "mesh"));
  b.set("center", Array<double>(), "m, dim components (default origin)");
  b.set("size", Array<double>(), "box extents (m)");
  b.set("inner radius", 0.0, "m (ring, half-ring)");
  b.set("outer radius", 0.0, "m (disk, sphere, ring, half-ring)");
  b.set("mesh file", std::string(""), "closed Gmsh MSH 4.1 mesh (shape mesh), relative to the scene");
  b.set("initial velocity", Array<double>(), "m/s, dim components (default 0)");
  return b;
}

ParameterList level_set_schema() {
  ParameterList l("level set");
  choice(l, "type", "half-plane",
         "solid where (x - point) . normal < 0, inside a box, or below/above the sine contour "
         "y = height + amplitude cos(2 pi x / wavelength) (extruded along z in 3D)",
         tuple<std::string>("half-plane", "box", "sine"));
  l.set("slip", false,
        "true: only the velocity along the level set's normal at each node inside is constrained "
        "(n . v = n . v_boundary), the tangential motion is free; false: no-slip");
  l.set("point", Array<double>(), "half-plane: a point on the plane (m)");
  l.set("normal", Array<double>(), "half-plane: normal pointing into the free side");
  l.set("box min", Array<double>(), "box: lower corner (m)");
  l.set("box max", Array<double>(), "box: upper corner (m)");
  l.set("height", 0.0, "sine: y of the contour's mean line (m)");
  l.set("amplitude", 0.0, "sine: amplitude A of the contour (m)");
  l.set("wavelength", 0.0, "sine: wavelength (m), > 0 for type sine");
  choice(l, "solid", "below", "sine: the solid side of the contour", tuple<std::string>("below", "above"));
  l.set("velocity", Array<double>(), "m/s, constant motion of the boundary (default 0)");
  l.set("until", 0.0, "s: the level set is removed at this time, > 0 (0: never)");
  l.sublist("Motion", false,
            "piecewise motion instead of velocity: segments of type velocity or fixed, in name order; "
            "at rest after the last")
      .disableRecursiveValidation();
  return l;
}

}  // namespace

const ParameterList& scene_child_schema(const std::string& container) {
  static const ParameterList mat = material_schema();
  static const ParameterList body = body_schema();
  static const ParameterList bc = bc_schema();
  static const ParameterList seg = segment_schema();
  static const ParameterList mpm = mpm_body_schema();
  static const ParameterList ls = level_set_schema();
  if (container == "MPM Bodies") return mpm;
  if (container == "Level Sets") return ls;
  if (container == "Materials") return mat;
  if (container == "FEM Bodies") return body;
  if (container == "Boundary Conditions") return bc;
  if (container == "Motion") return seg;
  throw std::logic_error("no child schema for " + container);
}

bool scene_is_container(const std::string& name) {
  return name == "Materials" || name == "FEM Bodies" || name == "Boundary Conditions" ||
         name == "Motion" || name == "MPM Bodies" || name == "Level Sets";
}

Teuchos::RCP<const ParameterList> scene_schema() {
  auto pl = Teuchos::rcp(new ParameterList("bfemp"));
  pl->set("dimension", 2, "2 (triangles, plane strain) or 3 (tetrahedra)");
  choice(*pl, "Solver", "implicit",
         "implicit: barrier-coupled Newton stepper (paper 000); explicit: multimaterial MPM with grid contact "
         "(paper 001; MPM bodies only)",
         tuple<std::string>("implicit", "explicit"));
  pl->set("gravity", Array<double>(), "m/s^2, dim components (default none)");
  auto& time = pl->sublist("Time", false, "time stepping");
  time.set("dt", 1e-3, "time step (s), > 0");
  time.set("end time", 1e-2, "simulated time (s), > 0");
  time.set("CFL", 0.5, "explicit: dt = CFL dx / max(c + |v|) when Time/dt is not given, in (0, 1]");
  choice(time, "integrator", "backward-euler", "paper Eqs. 21-22",
         tuple<std::string>("backward-euler", "newmark"));
  auto& nm = time.sublist("Newmark", false, "Newmark parameters (paper Eq. 21)");
  nm.set("alpha", 0.5, "");
  nm.set("beta", 0.25, "");
  nm.set("gamma", 0.5, "");
  auto& newton = pl->sublist("Newton", false, "projected Newton (paper Algorithm 2)");
  newton.set("eps_d", 1e-6, "stop when |p|_inf / dt < eps_d (m/s)");
  newton.set("max iterations", 200, "iteration cap per step; reaching it is an error");
  choice(newton, "hessian", "exact-if-definite",
         "exact-if-definite: the exact Hessian whenever Cholmod (or CG + BLOCK_CHOLMOD) finds it positive "
         "definite, else the projected one (other linear solvers: always projected); projected: "
         "PSD-projected stencil Hessians (paper Algorithm 2)",
         tuple<std::string>("projected", "exact-if-definite"));
  choice(newton, "line search", "wolfe",
         "wolfe: when the first step raises the energy, bisect on the sign of the directional derivative "
         "(strong Wolfe, c2 0.1) before halving; it lands in a friction stick zone that halving steps over. "
         "backtracking: halving only (the paper's)",
         tuple<std::string>("wolfe", "backtracking"));
  newton.set("fallback keep", Array<double>(tuple<double>(0.7, 0.3)),
             "exact-if-definite, after an indefinite exact Hessian: the fractions of each contact pair's negative "
             "curvature kept (its negative eigenvalues scaled by them), tried in turn before the full PSD "
             "projection; each in (0, 1), decreasing; [] projects at once. Measured on A7's twist: 0.7, 0.3 halves "
             "the Newton iterations of the projection");
  newton.set("log iterations", false,
             "print one line per Newton iteration to stderr: |p|_inf/dt, line-search step and its CCD/inversion "
             "bound, |rhs|, which Hessian");
  pl->set("Linear Solver", *linear_solver_schema(), "linear solver of each Newton iteration");
  auto& out = pl->sublist("Output", false, "output frames and progress");
  out.set("frame every", 10, "steps between HDF5/XDMF frames (frame 0 is the initial state)");
  out.set("progress every", 10, "steps between progress lines (0: none)");
  out.set("count penetrations", false,
          "per step, count the particles inside an FEM element or a level set's solid and the deepest "
          "level-set penetration (diagnostics.csv penetrations, penetration_depth; costs a spatial hash per step)");
  out.set("checkpoint every", 0,
          "steps between restart checkpoints (checkpoint.h5; 0: only at the end and on SIGINT/SIGTERM), >= 0");
  pl->sublist("Materials", false, "named materials").disableRecursiveValidation();
  pl->sublist("FEM Bodies", false, "named FEM bodies").disableRecursiveValidation();
  auto& mpm = pl->sublist("MPM", false, "background grid and transfers of the MPM bodies");
  mpm.set("grid spacing", 0.0, "dx (m) of the uniform grid, > 0 when there are MPM bodies");
  mpm.set("domain min", Array<double>(), "lower corner of the grid domain (m)");
  mpm.set("domain max", Array<double>(), "upper corner of the grid domain (m)");
  mpm.set("particles per cell", 4, "1, 4, 9, 16 (2D); 1, 8, 27 (3D)");
  choice(mpm, "transfer", "APIC", "paper Tables 1-3", tuple<std::string>("APIC", "PIC", "FLIP"));
  choice(mpm, "when particles leave", "error",
         "a particle whose B-spline stencil leaves the grid domain: stop with an error naming it and "
         "the step, or extend the grid by whole cells before the step",
         tuple<std::string>("error", "extend"));
  mpm.set("boxes per axis", Array<int>(),
          "MPI: the ranks' particle boxes along each axis ([x, y] or [x, y, z], each >= 1, their product the "
          "number of ranks); empty: the rank count's prime factors to the axes with the most grid cells per "
          "box (2 or 3 ranks: slabs along the axis with the most cells); not used on one rank");
  mpm.set("rebalance above", 1.2,
          "MPI: new box cuts when the ranks' particle counts reach largest / mean > this after a step "
          "(0: never; else > 1)");
  mpm.set("sort particles every", 0,
          "steps between reorders of the particles by grid cell, from step 1 (locality of the transfers and "
          "the assembly; the same run to round-off); 0: never; >= 0");
  pl->sublist("MPM Bodies", false, "named MPM bodies (particles)").disableRecursiveValidation();
  auto& ex = pl->sublist("Explicit", false, "explicit multimaterial MPM (Solver: explicit; paper 001)");
  choice(ex, "shape functions", "uGIMP", "grid shape functions", tuple<std::string>("uGIMP", "quadratic B-spline"));
  choice(ex, "update", "FLIP", "particle update (Eqs. 32, 38, 41)", tuple<std::string>("FLIP", "PIC", "XPIC"));
  ex.set("XPIC order", 5, "m of XPIC(m), >= 1");
  choice(ex, "XPIC correction", "corrected", "multimaterial term of Eq. 37 (uncorrected: without it)",
         tuple<std::string>("corrected", "uncorrected"));
  ex.set("contact passes", 2, "contact corrections per step: 2 (Eqs. 26, 31) or 1 (pass 2 only)");
  choice(ex, "strain update", "USF",
         "when F and the stress are updated (Eq. 28): USF before the forces from v^alpha (Eq. 26); USL after "
         "the momentum update from v^{alpha+} (Eq. 31); USAVG dt/2 before from v^alpha, dt/2 after from "
         "v^{alpha+}. USL / USAVG are NairnMPM's USL- / USAVG- (no second extrapolation); NairnMPM's default "
         "USAVG+ is not implemented. With 'contact passes: 1' USF strains from uncorrected velocities",
         tuple<std::string>("USF", "USL", "USAVG"));
  choice(ex, "normals", "LR", "contact normal and separation: logistic regression (Eqs. 19-25) or AG (Eq. 13)",
         tuple<std::string>("LR", "AG"));
  choice(ex, "separation", "velocity", "AG only: approach alone (Eq. 14) or CP offset (Eq. 16)",
         tuple<std::string>("velocity", "CP"));
  ex.set("CP", 0.8, "delta_c of Eq. 16 in cells, > 0");
  choice(ex, "law", "coulomb", "contact law of every pair of material classes (Eqs. 7-10)",
         tuple<std::string>("frictionless", "coulomb", "stick"));
  ex.set("mu", 0.0, "Coulomb friction coefficient, >= 0");
  ex.sublist("Contact Pairs", false,
             "per pair of material classes, overriding law and mu: keys '<material> : <material>', values "
             "'frictionless', 'stick' or 'coulomb <mu>'")
      .disableRecursiveValidation();
  ex.set("stress body", std::string(""), "MPM body whose mean axial stress goes to diagnostics.csv (default: all)");
  ex.set("stress axis", -1, "axis of that stress (0..dim-1; -1: the last axis)");
  ex.set("fixed dt", false,
         "true: Time/dt as given (refused above the CFL limit at t = 0); set by the loader when the scene gives Time/dt");
  pl->sublist("Level Sets", false, "grid boundaries of the MPM bodies").disableRecursiveValidation();
  auto& contact = pl->sublist("Contact", false,
                              "barrier contact between MPM particles and FEM boundaries (paper section 4); on when the "
                              "scene has both MPM and FEM bodies");
  contact.set("enabled", true, "false: MPM and FEM bodies pass through each other");
  contact.set("dhat", 1e-3, "contact activation distance (m), > 0");
  contact.set("kappa", 1e5, "barrier stiffness (Pa), > 0");
  contact.set("eps_v", 1e-3, "static-friction velocity bound (m/s), > 0");
  contact.set("graph margin", 3.0,
              "the matrix graph of a step holds the pairs within (1 + margin) dhat at its start, so that pairs the "
              "Newton iterates bring within dhat need no graph rebuild; >= 0 (a speed knob: results change only "
              "at round-off)");
  contact.set("friction", 0.0, "Coulomb coefficient mu of every MPM/FEM body pair, >= 0");
  contact.sublist("Friction Pairs", false,
                  "per-pair mu overriding 'friction': keys '<MPM body> : <FEM body>', or '<FEM body> : <FEM body>' "
                  "with FEM-FEM (spaces optional)")
      .disableRecursiveValidation();
  contact.set("friction iterations", 20, "cap of the outer friction loop per step (paper Algorithm 1), >= 1");
  contact.set("friction pass tolerance", 10.0,
              "the friction loop's passes stop Newton at this multiple of Newton/eps_d until a pass converges "
              "within it at its first iteration; later passes stop at eps_d, and the loop ends, as in the paper's "
              "Algorithm 1, at a pass whose first Newton direction is below eps_d (the same test; fewer Newton "
              "iterations: the ci twist to 1.2 s, 2302 -> 1765); >= 1 (1: every pass at eps_d)");
  contact.set("friction relaxation from", 7,
              "the first friction pass lagged at x_lag + omega (x - x_lag) with Aitken's omega in [0.05, 1] "
              "instead of at the last pass's x (the same fixed point; a loop that has not converged by then is "
              "usually oscillating: A6's plate pressing the ring at mu 10); the loop then ends only when x_lag "
              "is within eps_d dt of x too; >= 0 (0: never, the paper's plain lagging; 1 and 2 act as 3: Aitken "
              "needs two passes' residuals)");
  contact.set("force body", std::string(""), "FEM body whose contact force goes to diagnostics.csv (default: all)");
  contact.set("FEM-FEM", false,
              "true: the FEM bodies also contact each other (2D; boundary nodes against the other bodies' edges), "
              "also in scenes without MPM bodies");
  contact.set("check iterates", false,
              "debug: test every Newton iterate for particles inside FEM bodies; one found is an error");
  return pl;
}

}  // namespace bfemp
