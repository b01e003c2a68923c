#pragma once
// XDMF 3 index for a time series stored by Hdf5FrameWriter, so that ParaView
// (Xdmf3 reader) opens the run as one temporal series:
//
//   Domain / Grid "TimeSeries" (Collection, Temporal)
//     per frame: Grid (Uniform, with <Time>) when the frame holds one grid,
//                else Grid (Collection, Spatial, with <Time>) of Uniform grids
//                (e.g. "fem" triangles + "particles" polyvertex).
//
// After every add_frame() the whole .xdmf is rewritten atomically, so a reader
// only ever sees completed frames.
#include <cstddef>
#include <string>
#include <vector>

namespace bfemp {

struct XdmfTopology {
  std::string type;  // "Triangle", "Tetrahedron" or "Polyvertex"
  std::size_t num_cells = 0;
  int nodes_per_cell = 0;  // 3, 4 or 1
  // Connectivity dataset (int64, num_cells x nodes_per_cell), e.g.
  // "/mesh/cells". May be empty for Polyvertex (one cell per node implied).
  std::string dataset;
};

struct XdmfAttribute {
  std::string name;
  // Dataset path: relative to XdmfGrid::group unless it starts with '/'.
  std::string dataset;
  // 1 -> Scalar, 2 or 3 -> Vector, 6 -> Tensor6, 9 -> Tensor, other -> Matrix.
  int components = 1;
  bool integer = false;  // int64 dataset (default: float64)
};

struct XdmfGrid {
  std::string name;  // e.g. "fem", "particles"
  // HDF5 group the relative dataset names live in, e.g. "/frame_000003".
  std::string group;
  XdmfTopology topology;
  std::size_t num_nodes = 0;
  int dim = 0;  // 2 -> GeometryType "XY", 3 -> "XYZ"
  std::string geometry = "positions";  // num_nodes x dim float64
  std::vector<XdmfAttribute> node_attributes;  // num_nodes x components
  std::vector<XdmfAttribute> cell_attributes;  // num_cells x components
};

struct XdmfFrame {
  double time = 0.0;
  std::vector<XdmfGrid> grids;  // at least one
};

// The particle grid of frame `index` as bfemp writes it: "particles", a
// polyvertex over /mesh/particle_vertices, geometry particle_positions in the
// frame's group; the caller adds the attributes.
XdmfGrid xdmf_particle_grid(int index, std::size_t num_particles, int dim);

class XdmfSeriesWriter {
 public:
  // `xdmf_path`: the file to (re)write. `h5_name`: the HDF5 file as the .xdmf
  // should reference it, normally its name relative to the .xdmf's directory.
  XdmfSeriesWriter(std::string xdmf_path, std::string h5_name);

  // Validates the frame (std::invalid_argument naming the grid and field),
  // appends it and rewrites the .xdmf atomically.
  // With write = false the file is left as it is (restart adds the kept
  // frames in a batch, then writes once with the next add_frame or write()).
  void add_frame(const XdmfFrame& frame, bool write = true);
  void write() const;

  std::size_t num_frames() const { return frames_.size(); }
  const std::string& path() const { return xdmf_path_; }
  // The complete XML document for the frames added so far.
  std::string render() const;

 private:
  std::string xdmf_path_;
  std::string h5_name_;
  std::vector<std::string> frames_;  // rendered <Grid> element of each frame
};

}  // namespace bfemp
