// CCD time per query: point_triangle_ccd (kernels/contact/ccd.hpp, additive
// CCD, t_max = 1, default s_frac and iteration cap) on the 3085 vertex-face
// ground-truth queries of ../shared/data/ccd-queries/ (exact rationals,
// converted as in tests/common/ccd_queries.hpp). Serial: one query per call,
// as the line search evaluates them (threads do not change a query's time).
//
// Per query, the fastest of --repeats timed calls (a timer around each
// call); reported: their mean over the set (mean_per_query_s), the slowest
// query (worst_query_s, and which one), the median, and the best time of one
// untimed pass over the whole set divided by its size (set_pass_per_query_s,
// free of the timer's ~20 ns). Also the answers (hits, false negatives and
// false positives against the ground truth), which do not depend on timing.
//
//   bench_ccd [--data DIR] [--repeats N] [--out FILE]
// Writes JSON (default ccd.json) with one "results" entry that perf/compare.py
// matches on (dim, size, solver, threads); see perf/README.md.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "common/ccd_queries.hpp"
#include "kernels/contact/ccd.hpp"

using namespace bfemp;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double loadavg1() {
  double l = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}

struct Motion {
  Vec<3> x[4], d[4];
};

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(BFEMP_SOURCE_DIR) + "/../shared/data/ccd-queries";
  std::string out = "ccd.json";
  int repeats = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--repeats" && i + 1 < argc) repeats = std::atoi(argv[++i]);
    else {
      std::cerr << "usage: bench_ccd [--data DIR] [--repeats N] [--out FILE]\n";
      return 2;
    }
  }
  if (repeats < 1) {
    std::cerr << "bench_ccd: --repeats must be >= 1\n";
    return 2;
  }
  if (!std::filesystem::is_directory(data)) {
    std::cerr << "bench_ccd: no CCD query data at " << data << " (--data DIR)\n";
    return 2;
  }
  const auto set = ccd_queries::load_vertex_face_queries(data);
  const std::size_t n = set.queries.size();
  if (n == 0) {
    std::cerr << "bench_ccd: no vertex-face queries under " << data << "\n";
    return 2;
  }
  std::vector<Motion> m(n);
  for (std::size_t k = 0; k < n; ++k)
    for (int i = 0; i < 4; ++i) {
      const auto& a = set.queries[k].x0[i];
      const auto& b = set.queries[k].x1[i];
      m[k].x[i] = Vec<3>(a[0], a[1], a[2]);
      m[k].d[i] = Vec<3>(b[0], b[1], b[2]) - m[k].x[i];
    }
  auto ccd = [&](std::size_t k) {
    const Motion& q = m[k];
    return point_triangle_ccd(q.x[0], q.x[1], q.x[2], q.x[3], q.d[0], q.d[1], q.d[2], q.d[3], 1.0);
  };

  const double load_before = loadavg1();
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_seconds();
  std::vector<double> best(n, 1e300), step(n, 0.0);
  double pass_best = 1e300, sink = 0;
  for (int r = 0; r < repeats; ++r) {
    for (std::size_t k = 0; k < n; ++k) {  // timed one by one
      const auto s = std::chrono::steady_clock::now();
      const double t = ccd(k);
      const double e = std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count();
      best[k] = std::min(best[k], e);
      step[k] = t;
    }
    const auto s = std::chrono::steady_clock::now();  // one untimed pass
    for (std::size_t k = 0; k < n; ++k) sink += ccd(k);
    pass_best = std::min(pass_best, std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double cpu = cpu_seconds() - cpu0;

  std::size_t positives = 0, hits = 0, false_neg = 0, false_pos = 0, worst = 0;
  double sum = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const bool hit = step[k] < 1, truth = set.queries[k].truth == 1;
    positives += truth;
    hits += hit;
    false_neg += truth && !hit;
    false_pos += !truth && hit;
    sum += best[k];
    if (best[k] > best[worst]) worst = k;
  }
  std::vector<double> sorted = best;
  std::sort(sorted.begin(), sorted.end());
  const double mean = sum / n, median = sorted[n / 2];
  const std::string worst_name = set.queries[worst].file + " query " + std::to_string(set.queries[worst].index);

  std::printf("bench_ccd: %zu queries (%zu with contact), %d repeats: mean %.3f us, median %.3f us, worst %.1f us (%s), "
              "untimed pass %.3f us per query; false negatives %zu, false positives %zu; load average %.2f\n",
              n, positives, repeats, 1e6 * mean, 1e6 * median, 1e6 * best[worst], worst_name.c_str(),
              1e6 * pass_best / n, false_neg, false_pos, load_before);
  std::ostringstream j;
  j.precision(6);
  j << "{\n \"benchmark\": \"ccd_queries\",\n \"data\": \"" << json_escape(data) << "\",\n \"sink\": " << sink
    << ",\n \"results\": [\n  {\"config\": \"ccd/point_triangle/vertex-face\", \"dim\": 3, \"size\": \"" << n
    << "\", \"solver\": \"point_triangle_ccd\", \"threads\": 1"
    << ", \"queries\": " << n << ", \"positives\": " << positives << ", \"hits\": " << hits
    << ", \"false_negatives\": " << false_neg << ", \"false_positives\": " << false_pos
    << ", \"repeats\": " << repeats << ",\n   \"mean_per_query_s\": " << mean << ", \"median_per_query_s\": " << median
    << ", \"worst_query_s\": " << best[worst] << ", \"worst_query\": \"" << json_escape(worst_name) << "\""
    << ", \"set_pass_per_query_s\": " << pass_best / n << ", \"set_pass_s\": " << pass_best
    << ",\n   \"wall_s\": " << wall << ", \"cpu_utilisation\": " << (wall > 0 ? cpu / wall : 0.0)
    << ", \"loadavg_before\": " << load_before << "}\n ]\n}\n";
  std::ofstream f(out);
  if (!f) {
    std::cerr << "bench_ccd: cannot write " << out << "\n";
    return 2;
  }
  f << j.str();
  return false_neg > 0 ? 3 : 0;
}
