#pragma once
// The flat JSON the benchmarks write (perf/run_benchmarks.sh merges the runs,
// perf/compare.py reads them): a key -> raw value list in insertion order,
// numbers with 6 significant digits (non-finite: null), and the process's CPU
// seconds (user + system, all threads) for the utilisation figures.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include <sys/resource.h>

namespace bfemp::bench {

inline std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

inline std::string jnum(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

inline std::string jlist(const std::vector<double>& v) {
  std::string o = "[";
  for (std::size_t i = 0; i < v.size(); ++i) o += (i ? ", " : "") + jnum(v[i]);
  return o + "]";
}

struct Json {
  std::vector<std::pair<std::string, std::string>> kv;
  Json& num(const std::string& k, double v) { kv.emplace_back(k, jnum(v)); return *this; }
  Json& integer(const std::string& k, long long v) { kv.emplace_back(k, std::to_string(v)); return *this; }
  Json& str(const std::string& k, const std::string& v) { kv.emplace_back(k, jstr(v)); return *this; }
  Json& raw(const std::string& k, const std::string& v) { kv.emplace_back(k, v); return *this; }
  std::string dump(int indent) const {
    const std::string pad(indent + 2, ' ');
    std::string o = "{\n";
    for (std::size_t i = 0; i < kv.size(); ++i)
      o += pad + jstr(kv[i].first) + ": " + kv[i].second + (i + 1 < kv.size() ? ",\n" : "\n");
    return o + std::string(indent, ' ') + "}";
  }
};

// A JSON array of objects, one per line block.
inline std::string jarray(const std::vector<Json>& items, int indent) {
  std::string arr = "[\n";
  for (std::size_t i = 0; i < items.size(); ++i)
    arr += std::string(indent, ' ') + items[i].dump(indent) + (i + 1 < items.size() ? ",\n" : "\n");
  return arr + std::string(indent > 2 ? indent - 2 : 0, ' ') + "]";
}

inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + 1e-6 * u.ru_utime.tv_usec + u.ru_stime.tv_sec + 1e-6 * u.ru_stime.tv_usec;
}

// `--out FILE` and `--quick`, the options of the kernel benchmarks. Returns
// 0, or 2 after naming an unknown option.
struct BenchArgs {
  std::string out;
  bool quick = false;
};
inline int parse_bench_args(int argc, char** argv, const char* name, BenchArgs& args) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) args.out = argv[++i];
    else if (a == "--quick") args.quick = true;
    else {
      std::cerr << name << ": unknown option '" << a << "' (expected --out FILE, --quick)\n";
      return 2;
    }
  }
  return 0;
}

// Kokkos with OMP_NUM_THREADS threads (what run_benchmarks.sh sets).
inline Kokkos::InitArguments kokkos_args_from_env() {
  Kokkos::InitArguments ka;
  if (const char* s = std::getenv("OMP_NUM_THREADS")) ka.num_threads = std::atoi(s);
  return ka;
}

// Writes the top-level object; 0, or 1 after saying the file failed.
inline int write_json(const Json& top, const std::string& path, const char* name) {
  std::ofstream f(path);
  f << top.dump(0) << "\n";
  if (f) return 0;
  std::cerr << name << ": cannot write " << path << "\n";
  return 1;
}

}  // namespace bfemp::bench
