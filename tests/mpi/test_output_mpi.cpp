// Output of an MPI run (issue 9: one HDF5 file regardless of the rank count),
// on 1, 2 and 3 ranks:
// - particles_in_id_block / particle_values_in_id_block hand every rank its
//   contiguous block of ids in id order, every field intact, from particles
//   scattered over the ranks in any order (also all on one rank, or a rank
//   with none);
// - the parallel Hdf5FrameWriter (MPI-IO) writes the same file as the serial
//   writer given the whole data: replicated arrays from rank 0, each rank's
//   block of rows, static rows, frames kept and dropped on reopening;
// - bad rows on one rank throw on every rank (no rank is left in a
//   collective call), and the file stays usable;
// - a checkpoint written by R ranks (each its row block of the particle
//   arrays, rank 0 the replicated ones) reads back, for any reader rank count
//   and rank, as exactly that reader's rows (a rank with none included); one
//   without row blocks (older files) reads whole; a failure on one rank
//   throws on every rank and leaves the previous checkpoint and no .tmp file.
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Core.hpp>
#include <filesystem>
#include <mpi.h>
#include <string>
#include <vector>

#include "core/mpi_comm.hpp"
#include "io/checkpoint.hpp"
#include "io/hdf5_frames.hpp"
#include "mpm/particle_distribution.hpp"

namespace {

using namespace bfemp;

constexpr long long kTotal = 23;

// Every field of particle `id` is a distinct function of it.
double field(long long id, int f) { return 1000.0 * f + id + 0.25; }

// The particles of this rank: ids with (7 id) mod R == rank, in descending
// order (or, with all_on, every id on rank all_on and none elsewhere).
Particles<2> scattered(int me, int R, int all_on, Kokkos::View<long long*, MemSpace>& ids) {
  std::vector<long long> mine;
  for (long long id = kTotal - 1; id >= 0; --id)
    if (all_on >= 0 ? me == all_on : (7 * id) % R == me) mine.push_back(id);
  const std::size_t n = mine.size();
  Particles<2> p = allocate_particles<2>(n);
  ids = Kokkos::View<long long*, MemSpace>("ids", n);
  auto ih = Kokkos::create_mirror_view(ids);
  auto x = Kokkos::create_mirror_view(p.x);
  auto v = Kokkos::create_mirror_view(p.v);
  auto m = Kokkos::create_mirror_view(p.mass);
  auto V = Kokkos::create_mirror_view(p.volume0);
  auto F = Kokkos::create_mirror_view(p.F);
  auto C = Kokkos::create_mirror_view(p.C);
  auto b = Kokkos::create_mirror_view(p.body);
  auto mat = Kokkos::create_mirror_view(p.material);
  for (std::size_t q = 0; q < n; ++q) {
    const long long id = mine[q];
    ih(q) = id;
    for (int c = 0; c < 2; ++c) {
      x(q, c) = field(id, c);
      v(q, c) = field(id, 2 + c);
      for (int d = 0; d < 2; ++d) {
        F(q, c, d) = field(id, 4 + 2 * c + d);
        C(q, c, d) = field(id, 8 + 2 * c + d);
      }
    }
    m(q) = field(id, 12);
    V(q) = field(id, 13);
    b(q) = static_cast<int>(id % 3);
    mat(q) = static_cast<int>(id % 4);
  }
  Kokkos::deep_copy(ids, ih);
  Kokkos::deep_copy(p.x, x);
  Kokkos::deep_copy(p.v, v);
  Kokkos::deep_copy(p.mass, m);
  Kokkos::deep_copy(p.volume0, V);
  Kokkos::deep_copy(p.F, F);
  Kokkos::deep_copy(p.C, C);
  Kokkos::deep_copy(p.body, b);
  Kokkos::deep_copy(p.material, mat);
  return p;
}

void expect_block(int all_on) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), R = world->getSize();
  Kokkos::View<long long*, MemSpace> ids;
  const Particles<2> p = scattered(me, R, all_on, ids);
  const Particles<2> b = particles_in_id_block(p, ids, kTotal, *world);
  const long long lo = id_block_begin(kTotal, me, R), hi = id_block_begin(kTotal, me + 1, R);
  ASSERT_EQ(static_cast<long long>(b.size()), hi - lo);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.v);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.mass);
  auto V = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.volume0);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.F);
  auto C = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.C);
  auto bo = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.body);
  auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.material);
  for (long long q = 0; q < hi - lo; ++q) {
    const long long id = lo + q;
    for (int c = 0; c < 2; ++c) {
      EXPECT_EQ(x(q, c), field(id, c)) << "id " << id;
      EXPECT_EQ(v(q, c), field(id, 2 + c)) << "id " << id;
      for (int d = 0; d < 2; ++d) {
        EXPECT_EQ(F(q, c, d), field(id, 4 + 2 * c + d)) << "id " << id;
        EXPECT_EQ(C(q, c, d), field(id, 8 + 2 * c + d)) << "id " << id;
      }
    }
    EXPECT_EQ(m(q), field(id, 12));
    EXPECT_EQ(V(q), field(id, 13));
    EXPECT_EQ(bo(q), id % 3);
    EXPECT_EQ(mat(q), id % 4);
  }
  // Three values per particle, in this rank's particle order.
  Kokkos::View<double*, MemSpace> vals("vals", p.size() * 3);
  auto vh = Kokkos::create_mirror_view(vals);
  auto ih = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), ids);
  for (std::size_t q = 0; q < p.size(); ++q)
    for (int j = 0; j < 3; ++j) vh(q * 3 + j) = field(ih(q), 20 + j);
  Kokkos::deep_copy(vals, vh);
  const auto out = particle_values_in_id_block(vals, 3, ids, kTotal, *world);
  auto oh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), out);
  ASSERT_EQ(static_cast<long long>(oh.extent(0)), 3 * (hi - lo));
  for (long long q = 0; q < hi - lo; ++q)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(oh(q * 3 + j), field(lo + q, 20 + j)) << "id " << lo + q;
}

TEST(OutputMpi, IdBlocksFromScatteredParticles) { expect_block(-1); }

TEST(OutputMpi, IdBlocksFromOneRankHoldingAll) {
  auto world = Tpetra::getDefaultComm();
  expect_block(world->getSize() - 1);
}

std::string shared_path(const std::string& name) {
  auto world = Tpetra::getDefaultComm();
  const auto dir = std::filesystem::temp_directory_path() /
                   ("bfemp_output_mpi_np" + std::to_string(world->getSize()));
  if (world->getRank() == 0) std::filesystem::create_directories(dir);
  world->barrier();
  return (dir / name).string();
}

// Replicated FEM-like data, the particle rows and a static id column.
struct Data {
  std::vector<double> fem;           // 5 x 2
  std::vector<long long> cells;      // 4 x 3
  std::vector<double> rows;          // kTotal x 3
  std::vector<long long> ints;       // kTotal
};

Data data_of_frame(int frame) {
  Data d;
  for (int k = 0; k < 10; ++k) d.fem.push_back(field(k, 30 + frame));
  for (int k = 0; k < 12; ++k) d.cells.push_back(k % 5);
  for (long long id = 0; id < kTotal; ++id) {
    for (int j = 0; j < 3; ++j) d.rows.push_back(field(id, 40 + j + frame));
    d.ints.push_back(id * 10 + frame);
  }
  return d;
}

void write_frames(Hdf5FrameWriter& w, int first_frame, int frames, int me, int R, bool whole) {
  const long long lo = whole ? 0 : id_block_begin(kTotal, me, R), hi = whole ? kTotal : id_block_begin(kTotal, me + 1, R);
  const auto n = static_cast<std::size_t>(hi - lo), first = static_cast<std::size_t>(lo);
  for (int f = first_frame; f < first_frame + frames; ++f) {
    const Data d = data_of_frame(f);
    w.begin_frame(f, 0.5 * f, 10 * f);
    w.write_array("positions", d.fem.data(), 5, 2);
    w.write_rows("particle_velocities", d.rows.data() + 3 * lo, n, first, kTotal, 3);
    w.write_rows("particle_body", d.ints.data() + lo, n, first, kTotal, 1);
    w.end_frame();
  }
}

void write_file(const std::string& path, MPI_Comm comm, int me, int R) {
  Hdf5FrameWriter w(path, comm);
  const bool whole = !w.parallel();
  const Data d = data_of_frame(0);
  w.write_static("cells", d.cells.data(), 4, 3);
  const long long lo = whole ? 0 : id_block_begin(kTotal, me, R), hi = whole ? kTotal : id_block_begin(kTotal, me + 1, R);
  std::vector<long long> vertices;
  for (long long id = lo; id < hi; ++id) vertices.push_back(id);
  w.write_static_rows("particle_vertices", vertices.data(), vertices.size(), static_cast<std::size_t>(lo), kTotal, 1);
  write_frames(w, 0, 3, me, R, whole);
  w.close();
}

void expect_same_dataset(const std::string& a, const std::string& b, const std::string& path) {
  std::vector<std::size_t> sa, sb;
  const auto va = read_dataset(a, path, &sa);
  const auto vb = read_dataset(b, path, &sb);
  EXPECT_EQ(sa, sb) << path;
  EXPECT_EQ(va, vb) << path;
}

TEST(OutputMpi, ParallelWriterWritesTheSerialWritersFile) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), R = world->getSize();
  const std::string par = shared_path("parallel.h5"), ser = shared_path("serial.h5");
  write_file(par, raw_mpi_comm(*world), me, R);
  if (me == 0) write_file(ser, MPI_COMM_NULL, 0, 1);
  world->barrier();
  if (me == 0) {
    for (const char* p : {"/mesh/cells", "/mesh/particle_vertices"}) expect_same_dataset(par, ser, p);
    for (int f = 0; f < 3; ++f) {
      const std::string g = Hdf5FrameWriter::frame_group_name(f);
      for (const char* d : {"/positions", "/particle_velocities", "/particle_body"}) expect_same_dataset(par, ser, g + d);
      EXPECT_EQ(read_attribute(par, g, "time"), 0.5 * f);
      EXPECT_EQ(read_attribute(par, g, "step"), 10.0 * f);
      // Against the data themselves (not only the serial writer).
      const Data d = data_of_frame(f);
      EXPECT_EQ(read_dataset(par, g + "/particle_velocities", nullptr), d.rows);
      const auto ints = read_dataset_int(par, g + "/particle_body", nullptr);
      EXPECT_EQ(ints, d.ints);
    }
  }
  // Reopened on every rank (a restart from frame 1): frames 1 and 2 go, frame 1
  // is written again with other data (frame 4's).
  {
    Hdf5FrameWriter w(par, 1, raw_mpi_comm(*world));
    EXPECT_EQ(w.frame_time(0), 0.0);
    EXPECT_EQ(w.parallel(), R > 1);
    const Data d = data_of_frame(4);
    const long long lo = w.parallel() ? id_block_begin(kTotal, me, R) : 0;
    const long long hi = w.parallel() ? id_block_begin(kTotal, me + 1, R) : kTotal;
    w.begin_frame(1, 9.0, 90);
    w.write_rows("particle_velocities", d.rows.data() + 3 * lo, static_cast<std::size_t>(hi - lo),
                 static_cast<std::size_t>(lo), kTotal, 3);
    w.end_frame();
    w.close();
  }
  world->barrier();
  if (me == 0) {
    EXPECT_FALSE(dataset_exists(par, "/frame_000002/particle_velocities"));
    EXPECT_TRUE(dataset_exists(par, "/frame_000000/particle_velocities"));
    EXPECT_EQ(read_dataset(par, "/frame_000001/particle_velocities", nullptr), data_of_frame(4).rows);
    EXPECT_EQ(read_attribute(par, "/frame_000001", "time"), 9.0);
  }
}

TEST(OutputMpi, BadRowsOnOneRankThrowOnEveryRank) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), R = world->getSize();
  const std::string path = shared_path("bad_rows.h5");
  Hdf5FrameWriter w(path, raw_mpi_comm(*world));
  const Data d = data_of_frame(0);
  w.begin_frame(0, 0.0, 0);
  // The last rank claims rows past the end; on 1 rank (serial writer) a
  // partial block is itself refused.
  const long long lo = id_block_begin(kTotal, me, R), hi = id_block_begin(kTotal, me + 1, R);
  const std::size_t first = me == R - 1 ? static_cast<std::size_t>(lo) + 1 : static_cast<std::size_t>(lo);
  const std::size_t n = R == 1 ? 5 : static_cast<std::size_t>(hi - lo);
  EXPECT_ANY_THROW(w.write_rows("particle_velocities", d.rows.data() + 3 * lo, n, first, kTotal, 3));
  // Every rank went on alike: the next dataset is written by all.
  const std::size_t m = w.parallel() ? static_cast<std::size_t>(hi - lo) : kTotal;
  const std::size_t f0 = w.parallel() ? static_cast<std::size_t>(lo) : 0;
  w.write_rows("particle_body", d.ints.data() + f0, m, f0, kTotal, 1);
  w.end_frame();
  w.close();
  world->barrier();
  if (me == 0) {
    EXPECT_FALSE(dataset_exists(path, "/frame_000000/particle_velocities"));
    EXPECT_EQ(read_dataset_int(path, "/frame_000000/particle_body", nullptr), d.ints);
  }
}

// A checkpoint as every rank puts it: replicated text, attributes and FEM
// data; this rank's block [lo, hi) of kTotal particle rows (x: 3 columns,
// body: integers). bad: this rank's x with 0 columns.
Checkpoint checkpoint_of(int me, int R, double time, bool bad = false) {
  Checkpoint c;
  c.time = time;
  c.step = 7;
  c.frames = 3;
  c.dim = 3;
  c.texts["scene_source"] = "Time: {dt: 0.01}";
  const Data d = data_of_frame(static_cast<int>(time));
  c.put("fem_x", d.fem, 2);
  const long long lo = id_block_begin(kTotal, me, R), hi = id_block_begin(kTotal, me + 1, R);
  const auto first = static_cast<std::size_t>(lo);
  c.put_rows("particle_x", std::vector<double>(d.rows.begin() + 3 * lo, d.rows.begin() + 3 * hi), bad ? 0 : 3, first,
             kTotal);
  c.put_rows("particle_body", std::vector<long long>(d.ints.begin() + lo, d.ints.begin() + hi), 1, first, kTotal);
  // Two rows only: on 3 ranks rank 0 writes none, and readers of 3 or 4 get none.
  const long long tlo = id_block_begin(2, me, R), thi = id_block_begin(2, me + 1, R);
  c.put_rows("particle_tiny", std::vector<double>(d.rows.begin() + tlo, d.rows.begin() + thi), 1,
             static_cast<std::size_t>(tlo), 2);
  return c;
}

// Reader `r` of `n` gets rows [kTotal r / n, kTotal (r + 1) / n) of every
// blocked array, and every replicated one whole.
void expect_reads_back(const std::string& path, double time) {
  const Data d = data_of_frame(static_cast<int>(time));
  for (int n = 1; n <= 4; ++n)
    for (int r = 0; r < n; ++r) {
      const Checkpoint c = read_checkpoint(path, r, n);
      EXPECT_EQ(c.time, time);
      EXPECT_EQ(c.step, 7);
      EXPECT_EQ(c.text("scene_source"), "Time: {dt: 0.01}");
      EXPECT_EQ(c.real("fem_x", 5), d.fem);
      EXPECT_FALSE(c.array("fem_x").blocked);
      const long long lo = kTotal * r / n, hi = kTotal * (r + 1) / n;
      const CheckpointArray& x = c.array("particle_x");
      EXPECT_TRUE(x.blocked);
      EXPECT_EQ(x.first_row, static_cast<std::size_t>(lo)) << r << " of " << n;
      EXPECT_EQ(x.total_rows, static_cast<std::size_t>(kTotal));
      EXPECT_EQ(x.cols, 3u);
      EXPECT_EQ(c.real("particle_x", hi - lo), std::vector<double>(d.rows.begin() + 3 * lo, d.rows.begin() + 3 * hi));
      EXPECT_EQ(c.ints("particle_body", hi - lo), std::vector<long long>(d.ints.begin() + lo, d.ints.begin() + hi));
      const long long tlo = 2LL * r / n, thi = 2LL * (r + 1) / n;
      EXPECT_EQ(c.real("particle_tiny", thi - tlo), std::vector<double>(d.rows.begin() + tlo, d.rows.begin() + thi))
          << r << " of " << n;
    }
}

TEST(OutputMpi, CheckpointRowBlocksReadBackByAnyRankCount) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), R = world->getSize();
  const std::string path = shared_path("checkpoint.h5");
  write_checkpoint(path, checkpoint_of(me, R, 1.0), raw_mpi_comm(*world));
  // Every rank returns once the file is in place: each reads it at once.
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  expect_reads_back(path, 1.0);
}

// A checkpoint without row blocks (as written before 2026-12-07: every array
// put whole, no "blocked" attribute) reads whole for every reader.
TEST(OutputMpi, CheckpointWithoutRowBlocksReadsWholeOnEveryRank) {
  auto world = Tpetra::getDefaultComm();
  const std::string path = shared_path("checkpoint_whole.h5");
  if (world->getRank() == 0) {
    Checkpoint c = checkpoint_of(0, 1, 1.0);
    for (const char* name : {"particle_x", "particle_body"}) {  // the same arrays, put whole
      CheckpointArray& a = c.arrays.at(name);
      a.blocked = false;
      a.total_rows = a.rows;
    }
    write_checkpoint(path, c);
  }
  world->barrier();
  const Data d = data_of_frame(1);
  for (int n = 1; n <= 3; ++n)
    for (int r = 0; r < n; ++r) {
      const Checkpoint c = read_checkpoint(path, r, n);
      EXPECT_FALSE(c.array("particle_x").blocked);
      EXPECT_EQ(c.array("particle_x").first_row, 0u);
      EXPECT_EQ(c.real("particle_x", kTotal), d.rows);
      EXPECT_EQ(c.ints("particle_body", kTotal), d.ints);
    }
}

TEST(OutputMpi, CheckpointFailureOnOneRankThrowsOnEveryRankAndKeepsTheOldOne) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), R = world->getSize();
  const std::string path = shared_path("checkpoint_kept.h5");
  write_checkpoint(path, checkpoint_of(me, R, 1.0), raw_mpi_comm(*world));
  // The last rank's particle_x has 0 columns: refused before the collective
  // create, agreed on, so every rank throws and none waits.
  EXPECT_THROW(write_checkpoint(path, checkpoint_of(me, R, 2.0, me == R - 1), raw_mpi_comm(*world)),
               std::runtime_error);
  world->barrier();
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  expect_reads_back(path, 1.0);
  // The writer is usable again: the next good checkpoint replaces it.
  write_checkpoint(path, checkpoint_of(me, R, 2.0), raw_mpi_comm(*world));
  expect_reads_back(path, 2.0);
}

}  // namespace
