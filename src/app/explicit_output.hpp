#pragma once
// Output files of an explicit run (Solver: explicit), the same layout as the
// implicit run's so that ParaView, `bfemp probe` and the plotting scripts read
// both:
//   bfemp.h5         per frame (group /frame_%06d): particle_positions (np x dim, m),
//                    particle_velocities (np x dim, m/s), particle_stress (np x 9,
//                    Cauchy, Pa, a 3x3 row-major tensor; in 2D the plane components
//                    with zz = 0), particle_von_mises (Pa, of the in-plane stress in 2D),
//                    particle_pressure (-tr(sigma)/dim, Pa), particle_J (det F),
//                    particle_body, particle_material_class (int64);
//                    /mesh/particle_vertices: polyvertex connectivity 0..np-1
//   bfemp.xdmf       the ParaView time series over bfemp.h5 (completed frames only)
//   diagnostics.csv  one row per step (explicit_diagnostics_columns())
//   scene.yaml       the resolved scene
// Restart (`resume`): keeps the first `frames` frames and the rows through
// `step`, then appends.
#include <memory>
#include <string>
#include <vector>

#include "explicit/explicit_simulation.hpp"
#include "io/diagnostics_csv.hpp"
#include "io/hdf5_frames.hpp"
#include "io/scene.hpp"
#include "io/xdmf_writer.hpp"

namespace bfemp {

std::vector<std::string> explicit_diagnostics_columns();
std::vector<double> explicit_diagnostics_row(const ExplicitReport& r);

struct ExplicitResume {
  int frames = 0;
  long step = 0;
};

template <int dim>
class ExplicitOutput {
 public:
  ExplicitOutput(const std::string& dir, const Scene& scene, const ExplicitSimulation<dim>& sim,
                 const ExplicitResume* resume = nullptr);
  void write_frame(const ExplicitSimulation<dim>& sim);
  void write_diagnostics(const ExplicitReport& r) { csv_->write_row(explicit_diagnostics_row(r)); }
  void close() { h5_->close(); }
  int frames_written() const { return frame_; }

 private:
  XdmfFrame xdmf_frame(int index, double time) const;

  std::string dir_;
  std::size_t np_ = 0;
  std::unique_ptr<Hdf5FrameWriter> h5_;
  XdmfSeriesWriter xdmf_;
  std::unique_ptr<DiagnosticsCsv> csv_;
  int frame_ = 0;
};

}  // namespace bfemp
