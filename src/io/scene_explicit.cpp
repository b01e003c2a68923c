#include "io/scene_explicit.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "io/scene_messages.hpp"

namespace bfemp {

using Teuchos::ParameterList;
using scene_msg::bad;
using scene_msg::num;
using scene_msg::trim;

namespace {

// The materials used by MPM bodies (the classes), in Materials order.
std::vector<std::string> class_materials(const ParameterList& p) {
  const auto& mats = p.sublist("Materials");
  const auto& bodies = p.sublist("MPM Bodies");
  std::vector<std::string> out;
  for (auto it = mats.begin(); it != mats.end(); ++it)
    for (auto b = bodies.begin(); b != bodies.end(); ++b) {
      if (!bodies.entry(b).isList()) continue;
      const ParameterList& body = bodies.sublist(bodies.name(b));
      if (body.isType<std::string>("material") && body.get<std::string>("material") == mats.name(it)) {
        out.push_back(mats.name(it));
        break;
      }
    }
  return out;
}

xmpm::ContactLaw law_of(const std::string& name) {
  return name == "stick" ? xmpm::ContactLaw::Stick
         : name == "frictionless" ? xmpm::ContactLaw::Frictionless
                                  : xmpm::ContactLaw::Coulomb;
}

// One entry of Explicit/Contact Pairs: its key '<material> : <material>'
// as two class indices, its value 'frictionless', 'stick' or 'coulomb <mu>'.
struct PairLaw {
  int a = -1, b = -1;
  xmpm::LawParams law;
};

PairLaw parse_pair(const ParameterList& pairs, ParameterList::ConstIterator it, const std::vector<std::string>& classes) {
  const std::string name = pairs.name(it), key = "Explicit/Contact Pairs/" + name;
  const auto colon = name.find(':');
  auto index = [&](const std::string& m) {
    const auto f = std::find(classes.begin(), classes.end(), trim(m));
    return f == classes.end() ? -1 : static_cast<int>(f - classes.begin());
  };
  PairLaw r;
  if (colon != std::string::npos) {
    r.a = index(name.substr(0, colon));
    r.b = index(name.substr(colon + 1));
  }
  if (r.a < 0 || r.b < 0 || r.a == r.b)
    bad(key, "'" + name + "'",
        "a key '<material> : <material>' naming two different materials used by MPM bodies");
  const auto& e = pairs.entry(it);
  const std::string text = e.isType<std::string>() ? trim(Teuchos::getValue<std::string>(e)) : std::string();
  const std::string what = "'frictionless', 'stick' or 'coulomb <mu>' with mu >= 0";
  if (text.empty()) bad(key, e.isList() ? "(a sublist)" : Teuchos::toString(e.getAny()), what);
  const auto sp = text.find(' ');
  const std::string word = text.substr(0, sp);
  const std::string rest = sp == std::string::npos ? "" : trim(text.substr(sp + 1));
  if (word == "frictionless" || word == "stick") {
    if (!rest.empty()) bad(key, "'" + text + "'", what + " (no mu after '" + word + "')");
    r.law = {law_of(word), 0.0};
    return r;
  }
  if (word != "coulomb" || rest.empty()) bad(key, "'" + text + "'", what);
  std::size_t used = 0;
  double mu = -1;
  try {
    mu = std::stod(rest, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != rest.size() || !(mu >= 0) || !std::isfinite(mu)) bad(key, "'" + text + "'", what);
  r.law = {xmpm::ContactLaw::Coulomb, mu};
  return r;
}

}  // namespace

void check_solver_keys(ParameterList& raw) {
  const bool ex = raw.isParameter("Solver") && raw.isType<std::string>("Solver") &&
                  raw.get<std::string>("Solver") == "explicit";
  if (ex) {
    for (const char* k : {"Newton", "Linear Solver", "Contact", "FEM Bodies"})
      if (raw.isParameter(k))
        bad(k, "(given)", std::string("no '") + k + "' in an explicit scene (Solver: explicit; implicit-only key)");
    if (raw.isSublist("Time")) {
      auto& t = raw.sublist("Time");
      for (const char* k : {"integrator", "Newmark"})
        if (t.isParameter(k)) bad(std::string("Time/") + k, "(given)", "no implicit-only key in an explicit scene");
      if (t.isParameter("dt")) raw.sublist("Explicit").set("fixed dt", true);
    }
    if (raw.isSublist("MPM") && raw.sublist("MPM").isParameter("transfer"))
      bad("MPM/transfer", "(given)", "no implicit-only key in an explicit scene (use Explicit/update)");
    if (raw.isSublist("MPM") && raw.sublist("MPM").isParameter("sort particles every"))
      bad("MPM/sort particles every", "(given)", "no implicit-only key in an explicit scene (the explicit stepper "
                                                 "bins its particles by cell each step)");
    return;
  }
  if (raw.isParameter("Explicit")) bad("Explicit", "(given)", "'Solver: explicit' for the Explicit keys");
  if (raw.isSublist("Time") && raw.sublist("Time").isParameter("CFL"))
    bad("Time/CFL", "(given)", "'Solver: explicit' (the implicit stepper uses Time/dt)");
  if (raw.isSublist("Materials")) {
    const auto& mats = raw.sublist("Materials");
    for (auto it = mats.begin(); it != mats.end(); ++it) {
      if (!mats.entry(it).isList()) continue;
      const auto& m = mats.sublist(mats.name(it));
      if (m.isParameter("model") && m.isType<std::string>("model") && m.get<std::string>("model") == "hyperelastic-kg")
        bad("Materials/" + mats.name(it) + "/model", "'hyperelastic-kg'",
            "neo-hookean or linear in an implicit scene (hyperelastic-kg: Solver: explicit)");
    }
  }
}

bool is_explicit(const Scene& scene) { return scene.params.get<std::string>("Solver") == "explicit"; }

void check_explicit_values(const ParameterList& p) {
  if (p.get<std::string>("Solver") != "explicit") return;
  const auto& e = p.sublist("Explicit");
  const int m = e.get<int>("XPIC order");
  if (m < 1) bad("Explicit/XPIC order", std::to_string(m), "an integer >= 1");
  const int passes = e.get<int>("contact passes");
  if (passes != 1 && passes != 2) bad("Explicit/contact passes", std::to_string(passes), "1 or 2");
  const double cfl = p.sublist("Time").get<double>("CFL");
  if (!(cfl > 0 && cfl <= 1)) bad("Time/CFL", num(cfl), "a value in (0, 1]");
  const double mu = e.get<double>("mu");
  if (!(mu >= 0) || !std::isfinite(mu)) bad("Explicit/mu", num(mu), "a friction coefficient >= 0");
  const double cp = e.get<double>("CP");
  if (!(cp > 0)) bad("Explicit/CP", num(cp), "delta_c > 0 (cells)");
  const int dim = p.get<int>("dimension");
  const int ax = e.get<int>("stress axis");
  if (ax < -1 || ax >= dim) bad("Explicit/stress axis", std::to_string(ax), "-1 or 0.." + std::to_string(dim - 1));
  const std::string sb = e.get<std::string>("stress body");
  if (!sb.empty() && !p.sublist("MPM Bodies").isSublist(sb))
    bad("Explicit/stress body", "'" + sb + "'", "the name of an MPM body");
  if (p.sublist("MPM Bodies").numParams() == 0) bad("MPM Bodies", "{}", "at least one MPM body in an explicit scene");
  {  // per-pair laws: each names two classes, each unordered pair once
    const auto classes = class_materials(p);
    const auto& pairs = e.sublist("Contact Pairs");
    std::vector<int> seen(classes.size() * classes.size(), 0);
    for (auto it = pairs.begin(); it != pairs.end(); ++it) {
      const PairLaw r = parse_pair(pairs, it, classes);
      const std::size_t lo = std::min(r.a, r.b), hi = std::max(r.a, r.b);
      if (seen[lo * classes.size() + hi]++)
        bad("Explicit/Contact Pairs/" + pairs.name(it), "(given)",
            "each pair of materials once ('" + classes[lo] + " : " + classes[hi] + "' is given twice)");
    }
  }
  const auto& mats = p.sublist("Materials");
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    const auto& mt = mats.sublist(mats.name(it));
    if (mt.get<std::string>("model") != "hyperelastic-kg") continue;
    for (const char* k : {"K", "G"})
      if (!(mt.get<double>(k) > 0))
        bad("Materials/" + mats.name(it) + "/" + k, num(mt.get<double>(k)), std::string(k) + " > 0 (Pa)");
  }
}

template <int dim>
ExplicitSetup<dim> build_explicit_setup(const Scene& scene) {
  const ParameterList& p = scene.params;
  SimulationSetup<dim> base = build_setup<dim>(scene);
  ExplicitSetup<dim> s;
  s.grid = base.mpm->grid;
  s.particles = base.mpm->particles;
  s.body_names = base.mpm->body_names;
  s.level_sets = base.level_sets;
  for (const auto& ls : s.level_sets) {
    if (!ls.slip) continue;
    int nz = 0;
    for (int d = 0; d < dim; ++d) nz += ls.normal[d] != 0.0;
    if (nz != 1 || ls.kind != LevelSetKind::HalfPlane)
      bad("Level Sets/" + ls.name + "/slip", "true",
          "an axis-aligned half-plane for a slip (symmetry / piston) boundary of an explicit scene");
  }
  s.gravity = base.gravity;
  // material classes: the materials the MPM bodies use, in Materials order
  const auto& mats = p.sublist("Materials");
  std::vector<std::string> names;
  for (auto it = mats.begin(); it != mats.end(); ++it) names.push_back(mats.name(it));
  std::vector<int> used(names.size(), 0);
  const auto& bodies = p.sublist("MPM Bodies");
  for (auto it = bodies.begin(); it != bodies.end(); ++it) {
    const std::string m = bodies.sublist(bodies.name(it)).get<std::string>("material");
    used[std::find(names.begin(), names.end(), m) - names.begin()] = 1;
  }
  std::vector<int> cls(names.size(), -1);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!used[i])
      bad("Materials/" + names[i], "(no MPM body)", "a material class with particles (an MPM body using it)");
    cls[i] = static_cast<int>(s.materials.size());
    const auto& m = mats.sublist(names[i]);
    XMaterial xm;
    const std::string model = m.get<std::string>("model");
    xm.model = model == "hyperelastic-kg" ? XModel::HyperelasticKG : model == "linear" ? XModel::Linear : XModel::NeoHookean;
    xm.kg = {m.get<double>("K"), m.get<double>("G")};
    xm.lame = lame_from_young(m.get<double>("E"), m.get<double>("nu"));
    xm.density = m.get<double>("density");
    s.materials.push_back(xm);
    s.class_names.push_back(names[i]);
  }
  auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.particles.material);
  for (std::size_t q = 0; q < mat.extent(0); ++q) mat(q) = cls[mat(q)];
  Kokkos::deep_copy(s.particles.material, mat);
  const auto& e = p.sublist("Explicit");
  s.shape = e.get<std::string>("shape functions") == "uGIMP" ? XShape::UGimp : XShape::QuadraticBSpline;
  const std::string up = e.get<std::string>("update");
  s.update = up == "FLIP" ? XUpdate::FLIP : up == "PIC" ? XUpdate::PIC : XUpdate::XPIC;
  s.xpic_order = e.get<int>("XPIC order");
  s.xpic_corrected = e.get<std::string>("XPIC correction") == "corrected";
  s.contact_passes = e.get<int>("contact passes");
  const std::string su = e.get<std::string>("strain update");
  s.strain_update = su == "USL" ? XStrainUpdate::USL : su == "USAVG" ? XStrainUpdate::USAVG : XStrainUpdate::USF;
  s.normals = e.get<std::string>("normals") == "LR" ? XNormals::LR : XNormals::AG;
  s.separation = e.get<std::string>("separation") == "CP" ? XSeparation::CP : XSeparation::Velocity;
  s.cp_delta = e.get<double>("CP");
  const int M = static_cast<int>(s.materials.size());
  s.laws.assign(M * M, xmpm::LawParams{law_of(e.get<std::string>("law")), e.get<double>("mu")});
  const auto& pairs = e.sublist("Contact Pairs");
  for (auto it = pairs.begin(); it != pairs.end(); ++it) {
    const PairLaw r = parse_pair(pairs, it, s.class_names);
    s.laws[r.a * M + r.b] = s.laws[r.b * M + r.a] = r.law;
  }
  s.cfl = p.sublist("Time").get<double>("CFL");
  s.fixed_dt = e.get<bool>("fixed dt") ? p.sublist("Time").get<double>("dt") : 0.0;
  const std::string sb = e.get<std::string>("stress body");
  s.stress_body = -1;
  for (std::size_t b = 0; b < s.body_names.size(); ++b)
    if (s.body_names[b] == sb) s.stress_body = static_cast<int>(b);
  const int ax = e.get<int>("stress axis");
  s.stress_axis = ax < 0 ? dim - 1 : ax;
  return s;
}

template ExplicitSetup<2> build_explicit_setup<2>(const Scene&);
template ExplicitSetup<3> build_explicit_setup<3>(const Scene&);

}  // namespace bfemp
