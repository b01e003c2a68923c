#pragma once
// Everything a run writes into its output directory:
//   bfemp.h5        one group per frame (FEM positions, velocities, element
//                   von Mises stress and J), connectivity in /mesh
//   bfemp.xdmf      the ParaView time series over bfemp.h5 (completed frames only)
//   diagnostics.csv one row per step
//   scene.yaml      the resolved scene (every key, defaults filled in)
#include <memory>
#include <string>

#include "io/diagnostics_csv.hpp"
#include "io/hdf5_frames.hpp"
#include "io/scene.hpp"
#include "io/xdmf_writer.hpp"
#include "sim/simulation.hpp"

namespace bfemp {

// Column order of diagnostics.csv.
const std::vector<std::string>& diagnostics_columns();
std::vector<double> diagnostics_row(const StepReport& r);

template <int dim>
class RunOutput {
 public:
  RunOutput(const std::string& dir, const Scene& scene, const Simulation<dim>& sim);
  void write_frame(const Simulation<dim>& sim);
  void write_diagnostics(const StepReport& r) { csv_.write_row(diagnostics_row(r)); }
  void close() { h5_.close(); }
  int frames_written() const { return frame_; }

 private:
  std::string dir_;
  Hdf5FrameWriter h5_;
  XdmfSeriesWriter xdmf_;
  DiagnosticsCsv csv_;
  int frame_ = 0;
};

}  // namespace bfemp
