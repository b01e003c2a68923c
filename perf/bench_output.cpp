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
//   mpio_ind  the same with independent transfers.
// The file is written under --dir (default /tmp) and removed afterwards.
//   mpirun -np P bench_output [--particles 1000000] [--repeats 3] [--dir /tmp] [--out output.json]
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

// Rank 0 reads the file back and checks a few values of every field.
bool verify(const std::string& path, long long N) {
  hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return false;
  bool ok = true;
  for (int fi = 0; fi < 6 && ok; ++fi) {
    const Field& f = kFields[fi];
    hid_t d = H5Dopen2(file, f.name, H5P_DEFAULT);
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
  const double bytes = 144.0 * N;
  std::string rows;
  int code = 0;
  try {
    for (const char* s : {"gather", "mpio_coll", "mpio_ind"}) {
      double best = 1e300;
      for (int r = 0; r < repeats; ++r) {
        const std::string w = s;
        const double t = w == "gather" ? write_gather(path, N, rank, P) : write_mpio(path, N, rank, P, w == "mpio_coll");
        best = std::min(best, t);
      }
      bool ok = true;
      if (rank == 0) ok = verify(path, N);
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
  MPI_Finalize();
  return code;
}
