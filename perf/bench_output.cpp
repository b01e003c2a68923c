// One output frame of N particles written by P MPI ranks into one HDF5 file
// (issue 9: "one HDF5 file regardless of rank count: parallel HDF5 or a gather
// to rank 0 — measure which is cheaper at 1e6 particles").
//
// A frame holds what bfemp writes per particle: positions and velocities
// (N x 3 float64), the Cauchy stress (N x 9), von Mises, J (N) and the body id
// (N int64): 144 bytes per particle. Each rank owns a contiguous N/P slice.
// Strategies, each timed from the first byte leaving the ranks to the file
// closed and flushed (H5Fflush + fsync by closing), best of `repeats`:
//   gather    MPI_Gatherv of every field to rank 0, which writes the frame with
//             the serial HDF5 API (the file bfemp writes today);
//   mpio_coll parallel HDF5 (H5Pset_fapl_mpio), every rank writes its hyperslab
//             of each dataset with a collective transfer;
//   mpio_ind  the same with independent transfers;
//   bfemp     what `bfemp run` does on R ranks (src/app/run.cpp): the ranks
//             hold their particles as a slab cut leaves them (here rank r the
//             ids = r mod P, the worst case: (P-1)/P of them change rank),
//             particles_in_id_block redistributes every particle field into
//             contiguous id blocks, and Hdf5FrameWriter (MPI-IO, independent
//             transfers) writes each rank's block of rows. Its "stress" is F
//             and its von Mises and J the mass and volume (same bytes);
//   bfemp_gather what `bfemp run` did before (up to 9758db7): the same
//             particles gathered whole to rank 0 (gather_particles), which
//             writes them with the serial Hdf5FrameWriter;
//   checkpoint, checkpoint_gather  a restart checkpoint of the same particles
//             (224 bytes each), by id blocks through MPI-IO or gathered to
//             rank 0 (see write_checkpoint_bench).
// The file is written under --dir (default /tmp) and removed afterwards.
//   mpirun -np P bench_output [--particles 1000000] [--repeats 3] [--dir /tmp] [--out output.json]
#include <Kokkos_Core.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/hdf5_frames.hpp"
#include "mpm/particle_distribution.hpp"

namespace {

struct Field {
  const char* name;
  int cols;
  bool integer;
};
const Field kFields[] = {{"particle_positions", 3, false}, {"particle_velocities", 3, false},
                         {"particle_stress", 9, false},    {"particle_von_mises", 1, false},
                         {"particle_J", 1, false},         {"particle_body", 1, true}};

void check(herr_t e, const char* what) {
  if (e < 0) throw std::runtime_error(std::string("HDF5: ") + what + " failed");
}
hid_t check_id(hid_t id, const char* what) {
  if (id < 0) throw std::runtime_error(std::string("HDF5: ") + what + " failed");
  return id;
}

// This rank's slice [lo, hi) of N.
void slice(long long N, int rank, int P, long long& lo, long long& hi) {
  lo = N * rank / P;
  hi = N * (rank + 1) / P;
}

// Local data of one field (values depend on the global index, so a file can be checked).
std::vector<double> local_real(long long lo, long long hi, int cols, int f) {
  std::vector<double> v(static_cast<std::size_t>(hi - lo) * cols);
  for (long long q = lo; q < hi; ++q)
    for (int c = 0; c < cols; ++c) v[(q - lo) * cols + c] = 1e-3 * q + c + 10 * f;
  return v;
}
std::vector<long long> local_int(long long lo, long long hi) {
  std::vector<long long> v(hi - lo);
  for (long long q = lo; q < hi; ++q) v[q - lo] = q % 7;
  return v;
}

hid_t create_dataset(hid_t file, const Field& f, long long N) {
  const hsize_t dims[2] = {static_cast<hsize_t>(N), static_cast<hsize_t>(f.cols)};
  hid_t space = check_id(H5Screate_simple(f.cols == 1 ? 1 : 2, dims, nullptr), "H5Screate_simple");
  hid_t d = check_id(H5Dcreate2(file, f.name, f.integer ? H5T_STD_I64LE : H5T_IEEE_F64LE, space, H5P_DEFAULT,
                                H5P_DEFAULT, H5P_DEFAULT),
                     "H5Dcreate2");
  H5Sclose(space);
  return d;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double write_gather(const std::string& path, long long N, int rank, int P) {
  long long lo, hi;
  slice(N, rank, P, lo, hi);
  MPI_Barrier(MPI_COMM_WORLD);
  const auto t0 = std::chrono::steady_clock::now();
  hid_t file = -1;
  if (rank == 0) file = check_id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), "H5Fcreate");
  for (int fi = 0; fi < 6; ++fi) {
    const Field& f = kFields[fi];
    std::vector<int> counts(P), displs(P);
    for (int r = 0; r < P; ++r) {
      long long a, b;
      slice(N, r, P, a, b);
      counts[r] = static_cast<int>((b - a) * f.cols);
      displs[r] = static_cast<int>(a * f.cols);
    }
    if (f.integer) {
      const auto mine = local_int(lo, hi);
      std::vector<long long> all(rank == 0 ? N : 0);
      MPI_Gatherv(mine.data(), static_cast<int>(mine.size()), MPI_LONG_LONG, all.data(), counts.data(),
                  displs.data(), MPI_LONG_LONG, 0, MPI_COMM_WORLD);
      if (rank == 0) {
        hid_t d = create_dataset(file, f, N);
        check(H5Dwrite(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data()), "H5Dwrite");
        H5Dclose(d);
      }
    } else {
      const auto mine = local_real(lo, hi, f.cols, fi);
      std::vector<double> all(rank == 0 ? static_cast<std::size_t>(N) * f.cols : 0);
      MPI_Gatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(), displs.data(),
                  MPI_DOUBLE, 0, MPI_COMM_WORLD);
      if (rank == 0) {
        hid_t d = create_dataset(file, f, N);
        check(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data()), "H5Dwrite");
        H5Dclose(d);
      }
    }
  }
  if (rank == 0) {
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "H5Fflush");
    H5Fclose(file);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return seconds_since(t0);
}

double write_mpio(const std::string& path, long long N, int rank, int P, bool collective) {
  long long lo, hi;
  slice(N, rank, P, lo, hi);
  MPI_Barrier(MPI_COMM_WORLD);
  const auto t0 = std::chrono::steady_clock::now();
  hid_t fapl = check_id(H5Pcreate(H5P_FILE_ACCESS), "H5Pcreate");
  check(H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL), "H5Pset_fapl_mpio");
  hid_t file = check_id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), "H5Fcreate (mpio)");
  H5Pclose(fapl);
  hid_t xfer = check_id(H5Pcreate(H5P_DATASET_XFER), "H5Pcreate");
  check(H5Pset_dxpl_mpio(xfer, collective ? H5FD_MPIO_COLLECTIVE : H5FD_MPIO_INDEPENDENT), "H5Pset_dxpl_mpio");
  for (int fi = 0; fi < 6; ++fi) {
    const Field& f = kFields[fi];
    hid_t d = create_dataset(file, f, N);  // collective on every rank
    hid_t fs = H5Dget_space(d);
    const hsize_t start[2] = {static_cast<hsize_t>(lo), 0};
    const hsize_t count[2] = {static_cast<hsize_t>(hi - lo), static_cast<hsize_t>(f.cols)};
    check(H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, nullptr, count, nullptr), "H5Sselect_hyperslab");
    hid_t ms = H5Screate_simple(f.cols == 1 ? 1 : 2, count, nullptr);
    if (hi == lo) {
      H5Sselect_none(fs);
      H5Sselect_none(ms);
    }
    if (f.integer) {
      const auto mine = local_int(lo, hi);
      check(H5Dwrite(d, H5T_NATIVE_LLONG, ms, fs, xfer, mine.data()), "H5Dwrite (mpio)");
    } else {
      const auto mine = local_real(lo, hi, f.cols, fi);
      check(H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, xfer, mine.data()), "H5Dwrite (mpio)");
    }
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
  }
  H5Pclose(xfer);
  check(H5Fflush(file, H5F_SCOPE_GLOBAL), "H5Fflush");
  H5Fclose(file);
  MPI_Barrier(MPI_COMM_WORLD);
  return seconds_since(t0);
}

// Rank r's particles: ids r, r + P, r + 2P, ... (the worst case of a cut:
// (P-1)/P of them leave for another rank's id block). Every field of particle
// q is 1e-3 q + a per-field offset (x: +c, v: +c + 10, F: +3c + d + 20,
// mass: +30, volume0: +40; body q mod 7).
bfemp::Particles<3> scattered_particles(long long N, int rank, int P, Kokkos::View<long long*, bfemp::MemSpace>& ids) {
  using namespace bfemp;
  const long long mine = N / P + (rank < N % P ? 1 : 0);
  Particles<3> p = allocate_particles<3>(mine);
  ids = Kokkos::View<long long*, MemSpace>("ids", mine);
  Kokkos::parallel_for(
      "bench_output_particles", Kokkos::RangePolicy<ExecSpace>(0, mine), KOKKOS_LAMBDA(const long long k) {
        const long long q = rank + k * P;
        const double base = 1e-3 * q;
        ids(k) = q;
        for (int c = 0; c < 3; ++c) {
          p.x(k, c) = base + c;
          p.v(k, c) = base + c + 10;
          for (int d = 0; d < 3; ++d) p.F(k, c, d) = base + 3 * c + d + 20;
        }
        p.mass(k) = base + 30;
        p.volume0(k) = base + 40;
        p.body(k) = static_cast<int>(q % 7);
      });
  Kokkos::fence();
  return p;
}

// scattered_particles, then, timed from t0 (after a barrier), all of them on
// rank 0 (gather_particles; the other ranks get none) or each rank's id block
// (particles_in_id_block).
bfemp::Particles<3> redistributed(long long N, int rank, int P, bool gather,
                                  std::chrono::steady_clock::time_point& t0) {
  using namespace bfemp;
  const Teuchos::MpiComm<int> comm(MPI_COMM_WORLD);
  Kokkos::View<long long*, MemSpace> ids;
  const Particles<3> p = scattered_particles(N, rank, P, ids);
  MPI_Barrier(MPI_COMM_WORLD);
  t0 = std::chrono::steady_clock::now();
  return gather ? gather_particles(p, ids, N, comm) : particles_in_id_block(p, ids, N, comm);
}

double write_bfemp(const std::string& path, long long N, int rank, int P, bool gather) {
  using namespace bfemp;
  std::chrono::steady_clock::time_point t0;
  const Particles<3> b = redistributed(N, rank, P, gather, t0);
  if (gather && rank != 0) {  // rank 0 writes alone
    MPI_Barrier(MPI_COMM_WORLD);
    return seconds_since(t0);
  }
  const auto lo = static_cast<std::size_t>(gather ? 0 : id_block_begin(N, rank, P)), n = b.size(),
             total = static_cast<std::size_t>(N);
  Hdf5FrameWriter w(path, gather ? MPI_COMM_NULL : MPI_COMM_WORLD);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.v);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.F);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.mass);
  auto V = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.volume0);
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.body);
  const std::vector<long long> body64(body.data(), body.data() + n);
  // (In frame group 0, where verify() looks for them.)
  w.begin_frame(0, 0.0, 0);
  w.write_rows("particle_positions", x.data(), n, lo, total, 3);
  w.write_rows("particle_velocities", v.data(), n, lo, total, 3);
  w.write_rows("particle_stress", F.data(), n, lo, total, 9);
  w.write_rows("particle_von_mises", m.data(), n, lo, total, 1);
  w.write_rows("particle_J", V.data(), n, lo, total, 1);
  w.write_rows("particle_body", body64.data(), n, lo, total, 1);
  w.end_frame();
  w.close();
  MPI_Barrier(MPI_COMM_WORLD);
  return seconds_since(t0);
}

template <class V>
std::vector<double> host_reals(const V& v) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(h.data(), h.data() + h.size());
}

// A restart checkpoint of the particles (what make_checkpoint in
// src/app/run.cpp puts: x, v, mass, volume0, F, C, body, material; 224 bytes
// per particle): checkpoint = each rank its id block (particles_in_id_block,
// put_rows, write_checkpoint through MPI-IO, bfemp since 2026-12-07);
// checkpoint_gather = gather_particles to rank 0, which writes the whole set
// with the serial writer (bfemp before).
double write_checkpoint_bench(const std::string& path, long long N, int rank, int P, bool gather) {
  using namespace bfemp;
  std::chrono::steady_clock::time_point t0;
  const Particles<3> b = redistributed(N, rank, P, gather, t0);
  if (!gather || rank == 0) {
    const auto first = static_cast<std::size_t>(gather ? 0 : id_block_begin(N, rank, P)),
               total = static_cast<std::size_t>(N);
    Checkpoint c;
    c.dim = 3;
    c.texts["scene_source"] = "bench_output";
    c.put_rows("particle_x", host_reals(b.x), 3, first, total);
    c.put_rows("particle_v", host_reals(b.v), 3, first, total);
    c.put_rows("particle_mass", host_reals(b.mass), 1, first, total);
    c.put_rows("particle_volume0", host_reals(b.volume0), 1, first, total);
    c.put_rows("particle_F", host_reals(b.F), 9, first, total);
    c.put_rows("particle_C", host_reals(b.C), 9, first, total);
    auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.body);
    auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), b.material);
    c.put_rows("particle_body", std::vector<long long>(body.data(), body.data() + body.size()), 1, first, total);
    c.put_rows("particle_material", std::vector<long long>(mat.data(), mat.data() + mat.size()), 1, first, total);
    write_checkpoint(path, c, gather ? MPI_COMM_NULL : MPI_COMM_WORLD);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return seconds_since(t0);
}

bool verify_checkpoint(const std::string& path, long long N) {
  const bfemp::Checkpoint c = bfemp::read_checkpoint(path);
  const auto& v = c.real("particle_v", N);
  const auto& F = c.real("particle_F", N);
  const auto& body = c.ints("particle_body", N);
  bool ok = true;
  for (long long q = 0; ok && q < N; q += N / 97 + 1) {
    for (int k = 0; k < 3; ++k) ok = ok && v[q * 3 + k] == 1e-3 * q + k + 10;
    for (int k = 0; k < 9; ++k) ok = ok && F[q * 9 + k] == 1e-3 * q + k + 20;
    ok = ok && body[q] == q % 7;
  }
  return ok;
}

// Rank 0 reads the file back and checks a few values of every field (the
// datasets in the root group, or in group `group`).
bool verify(const std::string& path, long long N, const std::string& group = "") {
  hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return false;
  bool ok = true;
  for (int fi = 0; fi < 6 && ok; ++fi) {
    const Field& f = kFields[fi];
    hid_t d = H5Dopen2(file, (group + f.name).c_str(), H5P_DEFAULT);
    if (d < 0) {
      ok = false;
      break;
    }
    if (f.integer) {
      std::vector<long long> v(N);
      ok = H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0;
      for (long long q = 0; ok && q < N; q += N / 97 + 1) ok = v[q] == q % 7;
    } else {
      std::vector<double> v(static_cast<std::size_t>(N) * f.cols);
      ok = H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0;
      for (long long q = 0; ok && q < N; q += N / 97 + 1)
        for (int c = 0; c < f.cols; ++c) ok = ok && v[q * f.cols + c] == 1e-3 * q + c + 10 * fi;
    }
    H5Dclose(d);
  }
  H5Fclose(file);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  Kokkos::initialize(argc, argv);
  int rank = 0, P = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &P);
  long long N = 1000000;
  int repeats = 3;
  std::string dir = "/tmp", out;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--particles") N = std::atoll(argv[i + 1]);
    else if (a == "--repeats") repeats = std::atoi(argv[i + 1]);
    else if (a == "--dir") dir = argv[i + 1];
    else if (a == "--out") out = argv[i + 1];
  }
  const std::string path = dir + "/bench_output_" + std::to_string(P) + ".h5";
  std::string rows;
  int code = 0;
  try {
    for (const char* s :
         {"gather", "mpio_coll", "mpio_ind", "bfemp", "bfemp_gather", "checkpoint", "checkpoint_gather"}) {
      double best = 1e300;
      const std::string w = s;
      const bool ck = w.rfind("checkpoint", 0) == 0;
      const double bytes = (ck ? 224.0 : 144.0) * N;
      for (int r = 0; r < repeats; ++r) {
        const double t = w == "gather"  ? write_gather(path, N, rank, P)
                         : w == "bfemp" || w == "bfemp_gather" ? write_bfemp(path, N, rank, P, w != "bfemp")
                         : ck ? write_checkpoint_bench(path, N, rank, P, w != "checkpoint")
                                        : write_mpio(path, N, rank, P, w == "mpio_coll");
        best = std::min(best, t);
      }
      bool ok = true;
      if (rank == 0)
        ok = ck ? verify_checkpoint(path, N)
                : verify(path, N, w.rfind("bfemp", 0) == 0 ? bfemp::Hdf5FrameWriter::frame_group_name(0) + "/" : "");
      if (rank == 0) {
        std::remove(path.c_str());
        std::printf("%-10s %d rank(s), %lld particles: %.3f s per frame (%.0f MB/s)%s\n", s, P, N, best,
                    bytes / best / 1e6, ok ? "" : "  FILE CONTENT WRONG");
        char row[256];
        std::snprintf(row, sizeof row,
                      "%s    {\"strategy\": \"%s\", \"ranks\": %d, \"particles\": %lld, \"frame_s\": %.6g, "
                      "\"MB_per_s\": %.6g, \"verified\": %s}",
                      rows.empty() ? "" : ",\n", s, P, N, best, bytes / best / 1e6, ok ? "true" : "false");
        rows += row;
        if (!ok) code = 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_output: rank %d: %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  if (rank == 0 && !out.empty()) {
    std::ofstream f(out);
    f << "{\n  \"benchmark\": \"output_frame\",\n  \"bytes_per_particle\": 144,\n  \"results\": [\n" << rows
      << "\n  ]\n}\n";
  }
  Kokkos::finalize();
  MPI_Finalize();
  return code;
}
