// Value and start-state checks of a scene (see scene_checks.hpp).
#include "io/scene_checks.hpp"

#include <Teuchos_Array.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "io/scene_messages.hpp"

namespace bfemp {

using Teuchos::Array;
using Teuchos::ParameterList;

namespace {

using scene_msg::bad;
using scene_msg::list;
using scene_msg::num;
using scene_msg::trim;

void positive(const ParameterList& l, const std::string& path, const std::string& key, const std::string& what) {
  const double v = l.get<double>(key);
  if (!(v > 0)) bad(path + key, num(v), what);
}

void at_least(const ParameterList& l, const std::string& path, const std::string& key, int lo) {
  const int v = l.get<int>(key);
  if (v < lo) bad(path + key, std::to_string(v), ">= " + std::to_string(lo));
}

void check_time(const ParameterList& raw) {
  const auto& time = raw.sublist("Time");
  positive(time, "Time/", "dt", "dt > 0 (s)");
  positive(time, "Time/", "end time", "a positive time (s)");
  const double steps = time.get<double>("end time") / time.get<double>("dt");
  if (!(steps <= kMaxSteps))
    bad("Time/end time", num(time.get<double>("end time")),
        "at most " + num(kMaxSteps) + " steps of dt = " + num(time.get<double>("dt")) + " s (it makes " +
            num(std::ceil(steps)) + ")");
  const auto& nm = time.sublist("Newmark");
  positive(nm, "Time/Newmark/", "alpha", "alpha > 0");
  const double beta = nm.get<double>("beta"), gamma = nm.get<double>("gamma");
  if (!(beta > 0 && beta <= 0.5)) bad("Time/Newmark/beta", num(beta), "beta in (0, 0.5]");
  if (!(gamma >= 0.5 && gamma <= 1)) bad("Time/Newmark/gamma", num(gamma), "gamma in [0.5, 1]");
  positive(raw.sublist("Newton"), "Newton/", "eps_d", "eps_d > 0 (m/s)");
  at_least(raw.sublist("Newton"), "Newton/", "max iterations", 1);
  const auto keep = raw.sublist("Newton").get<Array<double>>("fallback keep");
  for (Array<double>::size_type k = 0; k < keep.size(); ++k)
    if (!(keep[k] > 0 && keep[k] < 1) || (k > 0 && !(keep[k] < keep[k - 1])))
      bad("Newton/fallback keep", list(keep),
          "fractions in (0, 1), each below the one before (e.g. [0.7, 0.3]; the full projection follows them)");
  at_least(raw.sublist("Output"), "Output/", "frame every", 1);
  at_least(raw.sublist("Output"), "Output/", "progress every", 0);
}

void check_materials(const ParameterList& raw) {
  const auto& mats = raw.sublist("Materials");
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    const auto& m = mats.sublist(mats.name(it));
    const std::string k = "Materials/" + mats.name(it) + "/";
    positive(m, k, "E", "E > 0 (Pa)");
    const double nu = m.get<double>("nu");
    if (!(nu > -1 && nu < 0.5)) bad(k + "nu", num(nu), "a Poisson ratio in (-1, 0.5)");
    positive(m, k, "density", "density > 0");
  }
  const auto& mpm_bodies = raw.sublist("MPM Bodies");
  if (raw.sublist("FEM Bodies").numParams() + mpm_bodies.numParams() == 0)
    bad("FEM Bodies", "{}", "at least one FEM or MPM body");
  for (const char* container : {"FEM Bodies", "MPM Bodies"}) {
    const auto& bodies = raw.sublist(container);
    for (auto it = bodies.begin(); it != bodies.end(); ++it) {
      const std::string mname = bodies.sublist(bodies.name(it)).get<std::string>("material");
      if (!mats.isSublist(mname))
        bad(std::string(container) + "/" + bodies.name(it) + "/material", "'" + mname + "'",
            "the name of an entry of Materials");
    }
  }
  // Body names label diagnostics.csv columns ("<body>.com_x"): one name, one body.
  const auto& fem_bodies = raw.sublist("FEM Bodies");
  for (auto it = mpm_bodies.begin(); it != mpm_bodies.end(); ++it)
    if (fem_bodies.isSublist(mpm_bodies.name(it)))
      bad("MPM Bodies/" + mpm_bodies.name(it), "'" + mpm_bodies.name(it) + "'",
          "a body name not used by an FEM body too");
}

void check_mpm(const ParameterList& raw, int dim) {
  if (raw.sublist("MPM Bodies").numParams() == 0) return;
  const auto& m = raw.sublist("MPM");
  positive(m, "MPM/", "grid spacing", "dx > 0 (m)");
  Array<double> box[2];
  const char* keys[2] = {"domain min", "domain max"};
  for (int i = 0; i < 2; ++i) {
    box[i] = m.get<Array<double>>(keys[i]);
    if (static_cast<int>(box[i].size()) != dim)
      bad(std::string("MPM/") + keys[i], list(box[i]), std::to_string(dim) + " components");
  }
  for (int d = 0; d < dim; ++d)
    if (!(box[1][d] > box[0][d]))
      throw std::invalid_argument("scene keys 'MPM/domain min' = " + list(box[0]) + " and 'MPM/domain max' = " +
                                  list(box[1]) + ": expected domain max > domain min in every component");
  const int ppc = m.get<int>("particles per cell");
  const bool ok = dim == 2 ? (ppc == 1 || ppc == 4 || ppc == 9 || ppc == 16) : (ppc == 1 || ppc == 8 || ppc == 27);
  if (!ok) bad("MPM/particles per cell", std::to_string(ppc), dim == 2 ? "1, 4, 9 or 16" : "1, 8 or 27");
  const auto bpa = m.get<Array<int>>("boxes per axis");
  if (!bpa.empty()) {
    bool positive = static_cast<int>(bpa.size()) == dim;
    for (const int b : bpa) positive = positive && b >= 1;
    if (!positive) {
      std::string v;
      for (std::size_t k = 0; k < bpa.size(); ++k) v += (k ? ", " : "") + std::to_string(bpa[k]);
      bad("MPM/boxes per axis", "[" + v + "]",
          std::to_string(dim) + " whole numbers >= 1 whose product is the number of ranks (or no key)");
    }
  }
  const double rb = m.get<double>("rebalance above");
  if (!(rb == 0 || (rb > 1 && std::isfinite(rb))))
    bad("MPM/rebalance above", num(rb), "0 (never) or a finite imbalance > 1 (largest / mean particles per rank)");
  const int se = m.get<int>("sort particles every");
  if (se < 0) bad("MPM/sort particles every", std::to_string(se), "0 (never) or a number of steps >= 1");
}

void check_contact(const ParameterList& raw) {
  const auto& c = raw.sublist("Contact");
  for (const char* k : {"dhat", "kappa", "eps_v"}) positive(c, "Contact/", k, "a positive value");
  if (!(c.get<double>("friction") >= 0)) bad("Contact/friction", num(c.get<double>("friction")), "mu >= 0");
  if (!(c.get<double>("graph margin") >= 0))
    bad("Contact/graph margin", num(c.get<double>("graph margin")), "a margin >= 0 (in multiples of dhat)");
  at_least(c, "Contact/", "friction iterations", 1);
  at_least(c, "Contact/", "friction relaxation from", 0);
  if (!(std::isfinite(c.get<double>("friction pass tolerance")) && c.get<double>("friction pass tolerance") >= 1.0))
    bad("Contact/friction pass tolerance", num(c.get<double>("friction pass tolerance")),
        "a finite multiple of Newton/eps_d >= 1 (1: every friction pass at eps_d)");
  const std::string fb = c.get<std::string>("force body");
  if (!fb.empty() && !raw.sublist("FEM Bodies").isSublist(fb))
    bad("Contact/force body", "'" + fb + "'", "the name of an FEM body");
}

}  // namespace

void check_friction_pairs(const ParameterList& raw) {
  const auto& c = raw.sublist("Contact");
  const auto& fem = raw.sublist("FEM Bodies");
  const auto& mpm = raw.sublist("MPM Bodies");
  const auto& pairs = c.sublist("Friction Pairs");
  for (auto it = pairs.begin(); it != pairs.end(); ++it) {
    const std::string name = pairs.name(it), key = "Contact/Friction Pairs/" + name;
    const auto colon = name.find(':');
    const bool fem_fem = c.get<bool>("FEM-FEM");
    const std::string a = colon == std::string::npos ? "" : trim(name.substr(0, colon));
    const std::string b = colon == std::string::npos ? "" : trim(name.substr(colon + 1));
    const bool a_ok = mpm.isSublist(a) || (fem_fem && fem.isSublist(a) && a != b);
    if (colon == std::string::npos || !a_ok || !fem.isSublist(b))
      bad(key, "'" + name + "'",
          fem_fem ? "a key '<MPM body> : <FEM body>' or '<FEM body> : <other FEM body>' naming bodies of the scene"
                  : "a key '<MPM body> : <FEM body>' naming bodies of the scene (FEM body pairs need "
                    "Contact/FEM-FEM: true)");
    const auto& e = pairs.entry(it);
    double mu = -1;
    if (e.isType<double>()) mu = Teuchos::getValue<double>(e);
    else if (e.isType<int>()) mu = Teuchos::getValue<int>(e);
    else bad(key, e.isList() ? "(no number)" : Teuchos::toString(e.getAny()), "a number mu >= 0");
    if (!(mu >= 0) || !std::isfinite(mu)) bad(key, num(mu), "a finite mu >= 0");
  }
}

void check_scene_values(const ParameterList& raw) {
  const int dim = raw.get<int>("dimension");
  if (dim != 2 && dim != 3) bad("dimension", std::to_string(dim), "2 or 3");
  check_time(raw);
  const auto g = raw.get<Array<double>>("gravity");
  if (!g.empty() && static_cast<int>(g.size()) != dim)
    bad("gravity", list(g), std::to_string(dim) + " components");
  check_materials(raw);
  check_mpm(raw, dim);
  check_contact(raw);
}

template <int dim>
void check_mpm_start(const MpmSetup<dim>& mpm) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm.particles.x);
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm.particles.body);
  const std::size_t n = x.extent(0);
  auto where = [&](std::size_t q) {
    std::string s = "(";
    for (int d = 0; d < dim; ++d) s += (d ? ", " : "") + num(x(q, d));
    return s + ")";
  };
  auto name = [&](std::size_t q) { return "MPM body '" + mpm.body_names.at(body(q)) + "'"; };
  if (!mpm.extend_domain) {
    const auto& g = mpm.grid;
    for (std::size_t q = 0; q < n; ++q) {
      Vec<dim> p;
      for (int d = 0; d < dim; ++d) p[d] = x(q, d);
      if (g.contains(p)) continue;
      std::string lo, hi;  // the box where a particle's stencil fits
      for (int d = 0; d < dim; ++d) {
        lo += (d ? ", " : "") + num(g.origin[d] + 0.5 * g.dx);
        hi += (d ? ", " : "") + num(g.origin[d] + (g.n_cells[d] - 0.5) * g.dx);
      }
      throw std::invalid_argument(name(q) + ": particle at " + where(q) +
                                  " lies outside the MPM grid domain [(" + lo + "), (" + hi +
                                  ")] (its B-spline stencil needs half a cell inside the grid); enlarge "
                                  "'MPM/domain min'/'MPM/domain max' or set 'MPM/when particles leave: extend'");
    }
  }
}

template <int dim>
void check_level_set_start(const MpmSetup<dim>& mpm, const std::vector<LevelSet>& level_sets) {
  if (level_sets.empty()) return;
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm.particles.x);
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm.particles.body);
  for (std::size_t q = 0; q < x.extent(0); ++q)  // particles first: the first in id order is named
    for (const LevelSet& ls : level_sets) {
      Vec<dim> p;
      for (int d = 0; d < dim; ++d) p[d] = x(q, d);
      const double phi = ls.phi<dim>(p, 0.0);
      if (!(phi < 0)) continue;
      std::string at = "(";
      for (int d = 0; d < dim; ++d) at += (d ? ", " : "") + num(x(q, d));
        throw std::invalid_argument("MPM body '" + mpm.body_names.at(body(q)) + "': particle at " + at +
                                    ")" + " starts inside the solid of level set '" + ls.name +
                                    "' (scene key 'Level Sets/" + ls.name + "', phi = " + num(phi) +
                                    " < 0); move the body or the level set so that the body starts on its free side");
    }
}

template void check_level_set_start<2>(const MpmSetup<2>&, const std::vector<LevelSet>&);
template void check_level_set_start<3>(const MpmSetup<3>&, const std::vector<LevelSet>&);
template void check_mpm_start<2>(const MpmSetup<2>&);
template void check_mpm_start<3>(const MpmSetup<3>&);

}  // namespace bfemp
