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

// Column order of diagnostics.csv: the step's totals, then for each body (in
// Simulation::body_names() order) "<body>.<field>" for the fields of
// body_column_fields() (mass, centre of mass, its velocity, kinetic and
// elastic energy).
std::vector<std::string> diagnostics_columns(const std::vector<std::string>& bodies);
const std::vector<const char*>& body_column_fields();
std::vector<double> diagnostics_row(const StepReport& r);

// Restart into the run's own directory: keep `frames` frames and the
// diagnostics rows through `step`, then append.
struct OutputResume {
  int frames = 0;
  long step = 0;
};

// This rank's rows of the particle datasets of a frame (MPI runs of MPM
// bodies): the particles with ids first .. first + particles.size() - 1, in id
// order (particles_in_id_block), and their contact forces (dim per particle;
// empty before the first contact report: zeros are written).
template <int dim>
struct ParticleRows {
  Particles<dim> particles;
  long long first = 0;
  Kokkos::View<const double*, MemSpace> contact_forces;
};

// MPI: with a communicator of R > 1 ranks every rank constructs the output and
// calls every member (collective); bfemp.h5 is written by all ranks through
// MPI-IO (Hdf5FrameWriter), the text files (bfemp.xdmf, diagnostics.csv,
// scene.yaml) by rank 0 alone (the others ignore write_diagnostics).
template <int dim>
class RunOutput {
 public:
  // A new output (files created or truncated), or with `resume` the
  // continuation of the directory's existing files.
  RunOutput(const std::string& dir, const Scene& scene, const Simulation<dim>& sim,
            const OutputResume* resume = nullptr, MPI_Comm comm = MPI_COMM_NULL);
  // MPI runs of MPM bodies pass this rank's rows of the particles (every
  // rank); otherwise the simulation's particles are written whole.
  void write_frame(const Simulation<dim>& sim, const ParticleRows<dim>* rows = nullptr);
  void write_diagnostics(const StepReport& r) {
    if (csv_) csv_->write_row(diagnostics_row(r));
  }
  void close() { h5_->close(); }
  int frames_written() const { return frame_; }
  const std::string& dir() const { return dir_; }

 private:
  XdmfFrame xdmf_frame(const Simulation<dim>& sim, int index, double time) const;

  std::string dir_;
  bool root_ = true;
  std::unique_ptr<Hdf5FrameWriter> h5_;
  XdmfSeriesWriter xdmf_;
  std::unique_ptr<DiagnosticsCsv> csv_;
  int frame_ = 0;
};

}  // namespace bfemp
