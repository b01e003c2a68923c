#include "io/scene.hpp"

#include <Teuchos_Array.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/collective_check.hpp"
#include "io/gmsh_reader.hpp"
#include "io/scene_checks.hpp"
#include "io/scene_explicit.hpp"
#include "io/scene_validate.hpp"
#include "io/scene_yaml.hpp"
#include "io/shape_mesher.hpp"
#include "mpm/particle_distribution.hpp"
#include "mpm/sampling.hpp"

#include "io/scene_messages.hpp"

namespace bfemp {

using Teuchos::Array;
using Teuchos::ParameterList;

namespace {

using scene_msg::bad;
using scene_msg::list;
using scene_msg::num;
using scene_msg::trim;

// Rethrows a sampling or meshing error ("sampling field 'outer_radius' = 0:
// expected ...") under the scene key it came from ("scene key 'MPM
// Bodies/disk/outer radius' = 0: expected ... (shape 'disk')").
[[noreturn]] void rethrow_under(const std::string& key, const std::string& shape, const std::invalid_argument& e) {
  static const std::regex field("^(sampling|shape) field '([a-z_]+)(\\[[0-9]+\\])?' = (.*)$");
  const std::string what = e.what();
  std::smatch m;
  if (!std::regex_match(what, m, field)) throw std::invalid_argument("scene key '" + key + "': " + what);
  std::string f = m[2];
  if (f == "dx") f = "(MPM/grid spacing)";
  else if (f == "kind") f = "shape";
  else std::replace(f.begin(), f.end(), '_', ' ');
  const std::string k = f[0] == '(' ? "MPM/grid spacing" : key + "/" + f;
  throw std::invalid_argument("scene key '" + k + std::string(m[3]) + "' = " + std::string(m[4]) +
                              " (shape '" + shape + "')");
}

Scene finish(ParameterList raw, const std::string& path, const std::string& base_dir,
             const std::vector<std::string>& overrides) {
  auto schema = scene_schema();
  if (raw.name() != "bfemp")
    throw std::invalid_argument((path.empty() ? std::string("scene") : "scene file '" + path + "'") +
                                ": top-level key '" + raw.name() + "', expected 'bfemp'");
  for (const auto& o : overrides) apply_scene_override(raw, *schema, o);
  if (raw.isSublist("Materials")) {  // an empty entry would run silently on every default
    const auto& mats = raw.sublist("Materials");
    for (auto it = mats.begin(); it != mats.end(); ++it)
      if (mats.entry(it).isList() && mats.sublist(mats.name(it)).numParams() == 0)
        bad("Materials/" + mats.name(it), "(nothing)", "a material with its keys (model, E, nu, density)");
  }
  check_solver_keys(raw);
  validate_scene_list(raw, *schema, "");
  check_scene_values(raw);
  check_explicit_values(raw);
  Scene s;
  s.path = path;
  s.base_dir = base_dir;
  s.params = raw;
  return s;
}

int index_of(const ParameterList& list, const std::string& name) {
  int i = 0;
  for (auto it = list.begin(); it != list.end(); ++it, ++i)
    if (list.name(it) == name) return i;
  return -1;
}

// Contact parameters; the friction table mu[mpm body * n_fem + fem body].
ContactParams contact_from(const ParameterList& p) {
  const auto& c = p.sublist("Contact");
  const auto& mpm = p.sublist("MPM Bodies");
  const auto& fem = p.sublist("FEM Bodies");
  ContactParams cp;
  cp.dhat = c.get<double>("dhat");
  cp.kappa = c.get<double>("kappa");
  cp.eps_v = c.get<double>("eps_v");
  cp.graph_margin = c.get<double>("graph margin");
  cp.friction_max_iterations = c.get<int>("friction iterations");
  cp.friction_pass_tolerance = c.get<double>("friction pass tolerance");
  cp.friction_relaxation_from = c.get<int>("friction relaxation from");
  const std::size_t nm = mpm.numParams(), nf = fem.numParams();
  cp.fem_fem = c.get<bool>("FEM-FEM");
  cp.mpm_bodies = static_cast<int>(nm);
  cp.mu.assign((cp.fem_fem ? nm + nf : nm) * nf, c.get<double>("friction"));
  const auto& pairs = c.sublist("Friction Pairs");
  for (auto it = pairs.begin(); it != pairs.end(); ++it) {
    const std::string key = "Contact/Friction Pairs/" + pairs.name(it);
    const std::string name = pairs.name(it);
    const auto colon = name.find(':');
    int a = colon == std::string::npos ? -1 : index_of(mpm, trim(name.substr(0, colon)));
    const int b = colon == std::string::npos ? -1 : index_of(fem, trim(name.substr(colon + 1)));
    int fa = -1;  // FEM-FEM: the first name is an FEM body
    if (a < 0 && cp.fem_fem && colon != std::string::npos) fa = index_of(fem, trim(name.substr(0, colon)));
    if (fa >= 0) a = static_cast<int>(nm) + fa;
    if (a < 0 || b < 0 || fa == b) bad(key, "'" + name + "'", "a key '<MPM body> : <FEM body>' naming bodies of the scene");
    const auto& e = pairs.entry(it);
    double mu = -1;
    if (e.isType<double>()) mu = Teuchos::getValue<double>(e);
    else if (e.isType<int>()) mu = Teuchos::getValue<int>(e);
    else bad(key, Teuchos::toString(e.getAny()), "a number mu >= 0");
    if (!(mu >= 0)) bad(key, num(mu), "mu >= 0");
    cp.mu[a * nf + b] = mu;
    if (fa >= 0) cp.mu[(nm + b) * nf + fa] = mu;  // symmetric
  }
  const std::string fb = c.get<std::string>("force body");
  cp.force_body = fb.empty() ? -1 : index_of(fem, fb);
  cp.check_iterates = c.get<bool>("check iterates");
  return cp;
}

std::array<double, 3> vec3(const Array<double>& a, int dim, const std::string& key) {
  std::array<double, 3> v{0, 0, 0};
  if (a.empty()) return v;
  if (static_cast<int>(a.size()) != dim) bad(key, list(a), std::to_string(dim) + " components");
  for (int i = 0; i < dim; ++i) v[i] = a[i];
  return v;
}

MeshData load_mesh(const ParameterList& mesh, const std::string& key, const std::string& base_dir, int dim) {
  const std::string file = mesh.get<std::string>("file");
  const std::string shape = mesh.get<std::string>("shape");
  if (!file.empty()) {
    std::filesystem::path p(file);
    if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
    if (!std::filesystem::exists(p))
      bad(key + "/file", "'" + file + "'", "an existing Gmsh .msh file (looked for " + p.string() + ")");
    return read_gmsh_msh4(p.string(), dim);
  }
  if (shape == "none") bad(key + "/shape", "'none' (and no 'file')", "a shape to mesh, or a 'file'");
  ShapeSpec spec;
  spec.kind = shape;
  const auto c = mesh.get<Array<double>>("center");
  spec.center.assign(c.begin(), c.end());
  const auto s = mesh.get<Array<double>>("size");
  spec.size.assign(s.begin(), s.end());
  spec.inner_radius = mesh.get<double>("inner radius");
  spec.outer_radius = mesh.get<double>("outer radius");
  spec.element_size = mesh.get<double>("element size");
  try {
    return mesh_shape(spec, dim);
  } catch (const std::invalid_argument& e) {
    rethrow_under(key, shape, e);
  }
}

MotionSegment segment_from(const ParameterList& s, int dim, const std::string& key) {
  MotionSegment seg;
  const std::string type = s.get<std::string>("type");
  seg.type = type == "velocity" ? MotionType::Velocity
             : type == "rotation" ? MotionType::Rotation : MotionType::Fixed;
  seg.duration = s.get<double>("duration");
  if (!(seg.duration > 0)) bad(key + "/duration", num(seg.duration), "a positive duration (s)");
  seg.velocity = vec3(s.get<Array<double>>("velocity"), dim, key + "/velocity");
  seg.angular_velocity = s.get<double>("angular velocity");
  seg.center = vec3(s.get<Array<double>>("center"), dim, key + "/center");
  const auto ax = s.get<Array<double>>("axis");
  if (!ax.empty()) {
    if (ax.size() != 3) bad(key + "/axis", list(ax), "3 components");
    seg.axis = {ax[0], ax[1], ax[2]};
    if (ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2] == 0) bad(key + "/axis", "[0,0,0]", "a non-zero axis");
  }
  if (seg.type == MotionType::Velocity && s.get<Array<double>>("velocity").empty())
    bad(key + "/velocity", "[]", std::to_string(dim) + " components for type velocity");
  return seg;
}

template <int dim>
Vec<dim> vecd(const Array<double>& a, const std::string& key) {
  if (static_cast<int>(a.size()) != dim) bad(key, list(a), std::to_string(dim) + " components");
  Vec<dim> v;
  for (int i = 0; i < dim; ++i) v(i) = a[i];
  return v;
}

// A start check of this rank's particles, through the block's agreement.
void block_check(const ParticleBlock& block, const std::function<void()>& check) {
  if (block.check) block.check(check);
  else check();
}

template <int dim>
void build_mpm(const Scene& scene, const std::vector<std::string>& mat_names, ParticleBlock block,
               SimulationSetup<dim>& setup) {
  const ParameterList& p = scene.params;
  const auto& bodies = p.sublist("MPM Bodies");
  if (bodies.numParams() == 0) return;
  const auto& m = p.sublist("MPM");
  const double dx = m.get<double>("grid spacing");
  MpmSetup<dim> mpm;
  const std::string tr = m.get<std::string>("transfer");
  mpm.scheme = tr == "PIC" ? TransferScheme::PIC : tr == "FLIP" ? TransferScheme::FLIP : TransferScheme::APIC;
  mpm.extend_domain = m.get<std::string>("when particles leave") == "extend";
  mpm.rebalance_above = m.get<double>("rebalance above");
  {
    const auto bpa = m.get<Array<int>>("boxes per axis");
    for (std::size_t d = 0; d < bpa.size() && d < 3; ++d) mpm.boxes_per_axis[d] = bpa[d];
  }
  mpm.sort_every = m.get<int>("sort particles every");
  try {
    mpm.grid = grid_covering<dim>(vecd<dim>(m.get<Array<double>>("domain min"), "MPM/domain min"),
                                  vecd<dim>(m.get<Array<double>>("domain max"), "MPM/domain max"), dx);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("scene sublist 'MPM': ") + e.what());
  }
  // Two passes over the bodies: count each one's particles (every rank the
  // same), then sample only this rank's id block of their concatenation
  // (block.count > 1; one block: every particle). Bodies that share a
  // lattice point overlap (sample_particles' lattice is the same for all).
  const int ppc = m.get<int>("particles per cell");
  struct Body {
    std::string key;
    SamplingShape shape;
    MeshData mesh;
    int material = 0;
    long long count = 0;
    std::array<double, 3> v0{0, 0, 0};
  };
  std::vector<Body> shapes;
  shapes.reserve(bodies.numParams());  // (shape.mesh points into the list)
  for (auto it = bodies.begin(); it != bodies.end(); ++it) {
    const std::string name = bodies.name(it);
    Body& body = shapes.emplace_back();
    body.key = "MPM Bodies/" + name;
    const auto& b = bodies.sublist(name);
    SamplingShape& shape = body.shape;
    shape.kind = b.get<std::string>("shape");
    const auto c = b.get<Array<double>>("center");
    shape.center.assign(c.begin(), c.end());
    const auto sz = b.get<Array<double>>("size");
    shape.size.assign(sz.begin(), sz.end());
    shape.inner_radius = b.get<double>("inner radius");
    shape.outer_radius = b.get<double>("outer radius");
    if (shape.kind == "mesh") {
      std::filesystem::path f(b.get<std::string>("mesh file"));
      if (f.is_relative()) f = std::filesystem::path(scene.base_dir) / f;
      if (!std::filesystem::exists(f))
        bad(body.key + "/mesh file", "'" + b.get<std::string>("mesh file") + "'", "an existing closed Gmsh .msh file");
      body.mesh = read_gmsh_msh4(f.string(), dim);
      shape.mesh = &body.mesh;
    }
    body.material = static_cast<int>(
        std::find(mat_names.begin(), mat_names.end(), b.get<std::string>("material")) - mat_names.begin());
    try {
      body.count = count_particles<dim>(shape, dx, ppc);
    } catch (const std::invalid_argument& e) {
      rethrow_under(body.key, shape.kind, e);
    }
    body.v0 = vec3(b.get<Array<double>>("initial velocity"), dim, body.key + "/initial velocity");
    mpm.body_names.push_back(name);
  }
  long long total = 0;
  for (const Body& b : shapes) total += b.count;
  const long long first = id_block_begin(total, block.rank, block.count),
                  end = id_block_begin(total, block.rank + 1, block.count);
  std::vector<Particles<dim>> parts;
  long long offset = 0;  // the body's first id
  for (std::size_t i = 0; i < shapes.size(); offset += shapes[i].count, ++i) {
    const Body& body = shapes[i];
    const long long lo = std::clamp(first - offset, 0LL, body.count), hi = std::clamp(end - offset, 0LL, body.count);
    if (lo == hi) continue;
    Particles<dim> part;
    try {
      part = sample_particles<dim>(body.shape, dx, ppc, setup.materials[body.material].density,
                                   static_cast<int>(i), body.material, lo, hi - lo);
    } catch (const std::invalid_argument& e) {
      rethrow_under(body.key, body.shape.kind, e);
    }
    for (int d = 0; d < dim; ++d) Kokkos::deep_copy(Kokkos::subview(part.v, Kokkos::ALL(), d), body.v0[d]);
    parts.push_back(part);
  }
  mpm.particles = concatenate(parts);
  if (block.count > 1) {
    mpm.particle_first = first;
    mpm.particle_total = total;
  }
  block_check(block, [&] { check_mpm_start(mpm); });
  {
    std::vector<SamplingShape> all;
    for (const Body& b : shapes) all.push_back(b.shape);
    int a = 0, b = 0;
    double x[dim];
    if (first_overlapping_pair<dim>(all, dx, ppc, a, b, x)) {
      std::string at;
      for (int d = 0; d < dim; ++d) at += (d ? ", " : "") + num(x[d]);
      throw std::invalid_argument("MPM body '" + mpm.body_names[a] + "' and MPM body '" + mpm.body_names[b] +
                                  "' overlap: both hold a particle at (" + at +
                                  ") (their samplings share a sub-cell centre); move their 'center' or change "
                                  "their sizes so the bodies are apart");
    }
  }
  setup.mpm = mpm;
  const auto& lss = p.sublist("Level Sets");
  for (auto it = lss.begin(); it != lss.end(); ++it) {
    const std::string key = "Level Sets/" + lss.name(it);
    const auto& l = lss.sublist(lss.name(it));
    LevelSet ls;
    ls.name = lss.name(it);
    const std::string type = l.get<std::string>("type");
    ls.kind = type == "box" ? LevelSetKind::Box : type == "sine" ? LevelSetKind::Sine : LevelSetKind::HalfPlane;
    ls.slip = l.get<bool>("slip");
    const double until = l.get<double>("until");
    if (!(until >= 0) || !std::isfinite(until)) bad(key + "/until", num(until), "a finite time >= 0 (s; 0: never removed)");
    if (until > 0) ls.until = until;
    ls.velocity = vec3(l.get<Array<double>>("velocity"), dim, key + "/velocity");
    const auto& motion = l.sublist("Motion");
    if (motion.numParams() > 0 && !l.get<Array<double>>("velocity").empty())
      bad(key + "/velocity", list(l.get<Array<double>>("velocity")), "no velocity when Motion segments are given");
    if (motion.numParams() > LevelSet::kMaxSegments)
      bad(key + "/Motion", std::to_string(motion.numParams()) + " segments",
          "at most " + std::to_string(LevelSet::kMaxSegments));
    double t_end = 0;
    for (auto sit = motion.begin(); sit != motion.end(); ++sit) {
      const std::string skey = key + "/Motion/" + motion.name(sit);
      const MotionSegment seg = segment_from(motion.sublist(motion.name(sit)), dim, skey);
      if (seg.type == MotionType::Rotation) bad(skey + "/type", "'rotation'", "velocity or fixed (level sets translate)");
      t_end += seg.duration;
      ls.seg_end[ls.segments] = t_end;
      for (int c = 0; c < 3; ++c) ls.seg_velocity[ls.segments][c] = seg.type == MotionType::Velocity ? seg.velocity[c] : 0.0;
      ++ls.segments;
    }
    if (ls.kind == LevelSetKind::HalfPlane) {
      ls.point = vec3(l.get<Array<double>>("point"), dim, key + "/point");  // default: origin
      const Vec<dim> n = vecd<dim>(l.get<Array<double>>("normal"), key + "/normal");
      if (!(n.norm() > 0) || !std::isfinite(n.norm()))
        bad(key + "/normal", list(l.get<Array<double>>("normal")), "a finite non-zero normal");
      const Vec<dim> u = n.normalized();
      for (int d = 0; d < dim; ++d) ls.normal[d] = u(d);
    } else if (ls.kind == LevelSetKind::Sine) {
      ls.height = l.get<double>("height");
      ls.amplitude = l.get<double>("amplitude");
      ls.wavelength = l.get<double>("wavelength");
      ls.solid_above = l.get<std::string>("solid") == "above";
      if (!std::isfinite(ls.height)) bad(key + "/height", num(ls.height), "a finite height (m)");
      if (!std::isfinite(ls.amplitude)) bad(key + "/amplitude", num(ls.amplitude), "a finite amplitude (m)");
      if (!(ls.wavelength > 0) || !std::isfinite(ls.wavelength))
        bad(key + "/wavelength", num(ls.wavelength), "a finite wavelength > 0 (m) for type sine");
    } else {
      const Vec<dim> lo = vecd<dim>(l.get<Array<double>>("box min"), key + "/box min");
      const Vec<dim> hi = vecd<dim>(l.get<Array<double>>("box max"), key + "/box max");
      for (int d = 0; d < dim; ++d) {
        ls.box_min[d] = lo(d);
        ls.box_max[d] = hi(d);
        if (!(hi(d) > lo(d)))
          bad(key + "/box max", list(l.get<Array<double>>("box max")),
              "every component > box min's (" + list(l.get<Array<double>>("box min")) + ")");
      }
    }
    setup.level_sets.push_back(ls);
  }
  block_check(block, [&] { check_level_set_start(*setup.mpm, setup.level_sets); });
}

}  // namespace

RunControl Scene::run_control() const {
  RunControl rc;
  rc.end_time = params.sublist("Time").get<double>("end time");
  rc.output_every = params.sublist("Output").get<int>("frame every");
  rc.progress_every = params.sublist("Output").get<int>("progress every");
  return rc;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("scene file '" + path + "': cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  const auto dir = std::filesystem::absolute(path).parent_path().string();
  return finish(*parse_scene_yaml(ss.str(), "scene file '" + path + "'"), path, dir, overrides);
}

Scene load_scene_from_string(const std::string& yaml, const std::string& base_dir,
                             const std::vector<std::string>& overrides) {
  return finish(*parse_scene_yaml(yaml, "scene"), "", base_dir, overrides);
}

ParticleBlock particle_block(const Teuchos::Comm<int>& comm) {
  ParticleBlock b;
  b.rank = comm.getRank();
  b.count = comm.getSize();
  const Teuchos::Comm<int>* c = &comm;
  b.check = [c](const std::function<void()>& check) { collective_check(*c, check); };
  return b;
}

template <int dim>
SimulationSetup<dim> build_setup(const Scene& scene, ParticleBlock block) {
  if (block.count < 1 || block.rank < 0 || block.rank >= block.count)
    throw std::logic_error("build_setup: particle block " + std::to_string(block.rank) + " of " +
                           std::to_string(block.count));
  const ParameterList& p = scene.params;
  SimulationSetup<dim> setup;
  std::vector<std::string> mat_names;
  const auto& mats = p.sublist("Materials");
  for (auto it = mats.begin(); it != mats.end(); ++it) {
    const auto& m = mats.sublist(mats.name(it));
    MaterialParams mp;
    mp.model = m.get<std::string>("model") == "linear" ? MaterialModel::LinearElastic : MaterialModel::NeoHookean;
    mp.lame = lame_from_young(m.get<double>("E"), m.get<double>("nu"));
    mp.density = m.get<double>("density");
    setup.materials.push_back(mp);
    mat_names.push_back(mats.name(it));
  }
  const auto& bodies = p.sublist("FEM Bodies");
  LO node_offset = 0;
  for (auto it = bodies.begin(); it != bodies.end(); ++it) {
    const std::string name = bodies.name(it);
    const std::string key = "FEM Bodies/" + name;
    const auto& b = bodies.sublist(name);
    FemBodyInput in;
    in.name = name;
    in.mesh = load_mesh(b.sublist("Mesh"), key + "/Mesh", scene.base_dir, dim);
    const std::string mname = b.get<std::string>("material");
    in.material_index = static_cast<int>(std::find(mat_names.begin(), mat_names.end(), mname) - mat_names.begin());
    setup.initial_velocity.push_back(vec3(b.get<Array<double>>("initial velocity"), dim, key + "/initial velocity"));
    const auto& bcs = b.sublist("Boundary Conditions");
    for (auto bit = bcs.begin(); bit != bcs.end(); ++bit) {
      const std::string bkey = key + "/Boundary Conditions/" + bcs.name(bit);
      const auto& bc = bcs.sublist(bcs.name(bit));
      PrescribedMotion mo;
      mo.name = name + "/" + bcs.name(bit);
      const std::string set = bc.get<std::string>("node set");
      const auto lo = bc.get<Array<double>>("box min"), hi = bc.get<Array<double>>("box max");
      if (!set.empty()) {
        auto f = in.mesh.node_sets.find(set);
        if (f == in.mesh.node_sets.end()) {
          std::string names;
          for (const auto& kv : in.mesh.node_sets) names += " '" + kv.first + "'";
          bad(bkey + "/node set", "'" + set + "'", "a node set of the mesh:" + (names.empty() ? " (none)" : names));
        }
        for (long long n : f->second) mo.nodes.push_back(node_offset + static_cast<LO>(n));
      } else {
        for (const auto& [k, a] : {std::pair{"box min", lo}, std::pair{"box max", hi}})
          if (static_cast<int>(a.size()) != dim)
            bad(bkey + "/" + k, list(a),
                std::to_string(dim) + " components (no 'node set' is given: 'box min' and 'box max' select the "
                "nodes)");
        for (std::size_t n = 0; n < in.mesh.num_nodes(); ++n) {
          bool inside = true;
          for (int c = 0; c < dim; ++c) {
            const double x = in.mesh.coords[n * dim + c];
            inside = inside && x >= lo[c] && x <= hi[c];
          }
          if (inside) mo.nodes.push_back(node_offset + static_cast<LO>(n));
        }
      }
      if (mo.nodes.empty())
        throw std::invalid_argument("scene keys '" + bkey + "/box min' = " + list(lo) + " and '" + bkey +
                                    "/box max' = " + list(hi) + ": expected a box holding at least one node of the mesh");
      const auto& motion = bc.sublist("Motion");
      for (auto sit = motion.begin(); sit != motion.end(); ++sit)
        mo.segments.push_back(segment_from(motion.sublist(motion.name(sit)), dim, bkey + "/Motion/" + motion.name(sit)));
      if (mo.segments.empty()) mo.segments.push_back(MotionSegment{});  // fixed
      setup.motions.push_back(std::move(mo));
    }
    node_offset += static_cast<LO>(in.mesh.num_nodes());
    setup.bodies.push_back(std::move(in));
  }
  build_mpm<dim>(scene, mat_names, block, setup);
  check_friction_pairs(p);
  const bool fem_fem = p.sublist("Contact").get<bool>("FEM-FEM");
  if (fem_fem && dim == 3) bad("Contact/FEM-FEM", "true", "false in a 3D scene (FEM-FEM contact is 2D only: 3D needs edge-edge pairs)");
  if (fem_fem && setup.bodies.size() < 2)
    bad("Contact/FEM-FEM", "true", "at least two FEM bodies (the scene has " + std::to_string(setup.bodies.size()) + ")");
  if (((setup.mpm && !setup.bodies.empty()) || fem_fem) && p.sublist("Contact").get<bool>("enabled"))
    setup.contact = contact_from(p);
  const auto& time = p.sublist("Time");
  setup.dt = time.get<double>("dt");
  setup.count_penetrations = p.sublist("Output").get<bool>("count penetrations");
  if (time.get<std::string>("integrator") == "newmark") {
    const auto& nm = time.sublist("Newmark");
    setup.integrator = TimeIntegrator::newmark(nm.get<double>("alpha"), nm.get<double>("beta"), nm.get<double>("gamma"));
  } else {
    setup.integrator = TimeIntegrator::backward_euler();
  }
  setup.gravity = vec3(p.get<Array<double>>("gravity"), dim, "gravity");
  setup.newton.eps_d = p.sublist("Newton").get<double>("eps_d");
  setup.newton.max_iterations = p.sublist("Newton").get<int>("max iterations");
  setup.newton.hessian = p.sublist("Newton").get<std::string>("hessian") == "exact-if-definite"
                             ? HessianMode::ExactIfDefinite
                             : HessianMode::Projected;
  setup.newton.line_search = p.sublist("Newton").get<std::string>("line search") == "wolfe" ? LineSearch::Wolfe
                                                                                              : LineSearch::Backtracking;
  setup.newton.log_iterations = p.sublist("Newton").get<bool>("log iterations");
  {
    const auto keep = p.sublist("Newton").get<Array<double>>("fallback keep");
    setup.newton.fallback_keep.assign(keep.begin(), keep.end());
  }
  setup.linear_solver = p.sublist("Linear Solver");
  return setup;
}

template SimulationSetup<2> build_setup<2>(const Scene&, ParticleBlock);
template SimulationSetup<3> build_setup<3>(const Scene&, ParticleBlock);

std::string scene_summary(const Scene& scene) {
  const auto& p = scene.params;
  std::ostringstream s;
  const auto& t = p.sublist("Time");
  const bool ex = is_explicit(scene);
  s << "scene " << (scene.path.empty() ? "(string)" : scene.path) << ": " << p.get<int>("dimension") << "D, ";
  if (ex) {
    const auto& e = p.sublist("Explicit");
    const std::string up = e.get<std::string>("update");
    s << "explicit multimaterial MPM, " << e.get<std::string>("shape functions") << ", "
      << (up == "XPIC" ? "XPIC(" + std::to_string(e.get<int>("XPIC order")) + ") " + e.get<std::string>("XPIC correction")
                       : up)
      << ", normals " << e.get<std::string>("normals");
    if (e.get<std::string>("normals") == "AG") s << " (" << e.get<std::string>("separation") << ")";
    s << ", " << e.get<int>("contact passes") << " contact pass(es), strain update " << e.get<std::string>("strain update")
      << ", law " << e.get<std::string>("law");
    if (e.get<std::string>("law") == "coulomb") s << " mu " << e.get<double>("mu");
    s << " (" << e.sublist("Contact Pairs").numParams() << " pair override(s)), ";
    if (e.get<bool>("fixed dt")) s << "dt " << t.get<double>("dt") << " s (fixed)";
    else s << "dt from CFL " << t.get<double>("CFL");
    s << " to " << t.get<double>("end time") << " s\n";
  } else {
    s << t.get<std::string>("integrator") << ", dt " << t.get<double>("dt") << " s to " << t.get<double>("end time")
      << " s, eps_d " << p.sublist("Newton").get<double>("eps_d") << " m/s, "
      << (p.sublist("Newton").get<std::string>("hessian") == "projected" ||
                  p.sublist("Linear Solver").get<std::string>("type") != "Cholmod"
              ? "projected Hessian"
              : "exact Hessian where definite")
      << ", line search " << p.sublist("Newton").get<std::string>("line search") << "\n";
  }
  const auto& bodies = p.sublist("FEM Bodies");
  for (auto it = bodies.begin(); it != bodies.end(); ++it) {
    const auto& b = bodies.sublist(bodies.name(it));
    const auto& mesh = b.sublist("Mesh");
    const auto& m = p.sublist("Materials").sublist(b.get<std::string>("material"));
    s << "  FEM body '" << bodies.name(it) << "': "
      << (mesh.get<std::string>("file").empty() ? mesh.get<std::string>("shape") : mesh.get<std::string>("file"))
      << ", " << m.get<std::string>("model") << " E " << m.get<double>("E") << " nu " << m.get<double>("nu")
      << " rho " << m.get<double>("density") << ", "
      << b.sublist("Boundary Conditions").numParams() << " prescribed set(s)\n";
  }
  const auto& mpm = p.sublist("MPM Bodies");
  for (auto it = mpm.begin(); it != mpm.end(); ++it) {
    const auto& b = mpm.sublist(mpm.name(it));
    const auto& m = p.sublist("Materials").sublist(b.get<std::string>("material"));
    s << "  MPM body '" << mpm.name(it) << "': " << b.get<std::string>("shape") << ", " << m.get<std::string>("model");
    if (m.get<std::string>("model") == "hyperelastic-kg") s << " K " << m.get<double>("K") << " G " << m.get<double>("G");
    else s << " E " << m.get<double>("E") << " nu " << m.get<double>("nu");
    s << " rho " << m.get<double>("density") << "\n";
  }
  if (mpm.numParams() > 0)
    s << "  MPM grid dx " << p.sublist("MPM").get<double>("grid spacing") << ", "
      << p.sublist("MPM").get<int>("particles per cell") << " particles per cell, "
      << (ex ? std::string() : p.sublist("MPM").get<std::string>("transfer") + ", ")
      << p.sublist("Level Sets").numParams() << " level set(s)\n";
  const auto& c = p.sublist("Contact");
  if (((mpm.numParams() > 0 && bodies.numParams() > 0) || c.get<bool>("FEM-FEM")) && c.get<bool>("enabled"))
    s << "  contact" << (c.get<bool>("FEM-FEM") ? " (FEM-FEM too)" : "") << ": barrier dhat " << c.get<double>("dhat") << " m, kappa " << c.get<double>("kappa")
      << " Pa, friction " << c.get<double>("friction") << " (" << c.sublist("Friction Pairs").numParams()
      << " pair override(s)), eps_v " << c.get<double>("eps_v") << " m/s\n";
  return s.str();
}

}  // namespace bfemp
