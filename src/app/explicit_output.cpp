#include "app/explicit_output.hpp"

#include <Teuchos_YamlParameterListHelpers.hpp>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "io/atomic_file.hpp"

namespace bfemp {

std::vector<std::string> explicit_diagnostics_columns() {
  return {"step",           "time",           "dt",           "dt_limit",      "contact_nodes", "multi_nodes",
          "active_nodes",   "lr_iter_mean",   "lr_iter_max",  "stress_body_Pa", "stress_all_Pa", "momentum_x",
          "momentum_y",     "momentum_z",     "kinetic",      "step_s"};
}

std::vector<double> explicit_diagnostics_row(const ExplicitReport& r) {
  return {static_cast<double>(r.step),
          r.time,
          r.dt,
          r.dt_limit,
          static_cast<double>(r.contact_nodes),
          static_cast<double>(r.multi_nodes),
          static_cast<double>(r.active_nodes),
          r.lr_iter_mean,
          static_cast<double>(r.lr_iter_max),
          r.stress_body,
          r.stress_all,
          r.momentum[0],
          r.momentum[1],
          r.momentum[2],
          r.kinetic,
          r.step_s};
}

namespace {

std::string prepare(const std::string& dir) {
  std::filesystem::create_directories(dir);
  return dir;
}

const std::set<std::string> kIntegerColumns = {"step", "contact_nodes", "multi_nodes", "active_nodes", "lr_iter_max"};

}  // namespace

template <int dim>
ExplicitOutput<dim>::ExplicitOutput(const std::string& dir, const Scene& scene, const ExplicitSimulation<dim>& sim,
                                    const ExplicitResume* resume)
    : dir_(prepare(dir)), np_(sim.particles().size()), xdmf_(dir + "/bfemp.xdmf", "bfemp.h5") {
  if (resume) {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5", resume->frames);
    csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", explicit_diagnostics_columns(), kIntegerColumns,
                                            resume->step);
    for (int i = 0; i < resume->frames; ++i) xdmf_.add_frame(xdmf_frame(i, h5_->frame_time(i)), false);
    xdmf_.write();
    frame_ = resume->frames;
  } else {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5");
    csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", explicit_diagnostics_columns(), kIntegerColumns);
    // Explicit polyvertex connectivity: without it ParaView draws no particles.
    std::vector<long long> ids(np_);
    for (std::size_t q = 0; q < np_; ++q) ids[q] = static_cast<long long>(q);
    h5_->write_static("particle_vertices", ids.data(), np_, 1);
  }
  std::ostringstream yaml;
  yaml << std::showpoint;
  Teuchos::writeParameterListToYamlOStream(scene.params, yaml);
  write_file_atomically(dir + "/scene.yaml", yaml.str());
}

template <int dim>
XdmfFrame ExplicitOutput<dim>::xdmf_frame(int index, double time) const {
  XdmfGrid g = xdmf_particle_grid(index, np_, dim);
  g.node_attributes = {{"velocity", "particle_velocities", dim},
                       {"stress", "particle_stress", 9},
                       {"von_mises", "particle_von_mises", 1},
                       {"pressure", "particle_pressure", 1},
                       {"J", "particle_J", 1},
                       {"body", "particle_body", 1, true},
                       {"material_class", "particle_material_class", 1, true}};
  return XdmfFrame{time, {g}};
}

template <int dim>
void ExplicitOutput<dim>::write_frame(const ExplicitSimulation<dim>& sim) {
  const auto& p = sim.particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto s = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.sigma);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.F);
  auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
  auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.cls);
  const std::size_t n = np_;
  std::vector<double> xs(n * dim), vs(n * dim), ss(n * 9, 0.0), vm(n), pr(n), J(n);
  std::vector<long long> bs(n), cs(n);
  for (std::size_t q = 0; q < n; ++q) {
    double S[3][3] = {};
    Mat<dim> Fq;
    for (int d = 0; d < dim; ++d) {
      xs[q * dim + d] = x(q, d);
      vs[q * dim + d] = v(q, d);
      for (int e = 0; e < dim; ++e) {
        S[d][e] = s(q, d, e);
        Fq(d, e) = F(q, d, e);
      }
    }
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) ss[q * 9 + d * 3 + e] = S[d][e];
    const double tr = S[0][0] + S[1][1] + S[2][2];
    double dev2 = 0;  // s:s of the deviator
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) {
        const double sd = S[d][e] - (d == e ? tr / 3.0 : 0.0);
        dev2 += sd * sd;
      }
    vm[q] = std::sqrt(1.5 * dev2);
    pr[q] = 0.0 - tr / dim;  // (0 - 0 = +0: no -0 in the file)
    J[q] = Fq.determinant();
    bs[q] = b(q);
    cs[q] = c(q);
  }
  h5_->begin_frame(frame_, sim.time(), sim.step_index());
  h5_->write_array("particle_positions", xs.data(), n, dim);
  h5_->write_array("particle_velocities", vs.data(), n, dim);
  h5_->write_array("particle_stress", ss.data(), n, 9);
  h5_->write_array("particle_von_mises", vm.data(), n, 1);
  h5_->write_array("particle_pressure", pr.data(), n, 1);
  h5_->write_array("particle_J", J.data(), n, 1);
  h5_->write_array("particle_body", bs.data(), n, 1);
  h5_->write_array("particle_material_class", cs.data(), n, 1);
  h5_->end_frame();
  xdmf_.add_frame(xdmf_frame(frame_, sim.time()));
  ++frame_;
}

template class ExplicitOutput<2>;
template class ExplicitOutput<3>;

}  // namespace bfemp
