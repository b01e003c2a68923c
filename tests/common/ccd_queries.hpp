#pragma once
// The vertex-face CCD ground-truth queries of ../shared/data/ccd-queries/
// (Wang et al. 2021 sample queries; format in that directory's README): every
// 8 rows are one query (point, triangle vertices at t = 0, then the same at
// t = 1), 7 integers per row: x, y, z as numerator/denominator pairs and the
// ground truth (1: the point touches the triangle for some t in [0, 1]).
//
// Conversion of the rationals: the numerators and denominators are parsed as
// arbitrary-size integers (the denominators reach 2^111, beyond any native
// integer type) and n / d is rounded to the nearest double, ties to even, by
// exact binary long division (54 quotient bits, then a sticky bit from the
// remainder): exactly what the rational's nearest double is, with no double
// rounding (long double division of two long doubles would be correct only
// while both are exact in a 64-bit mantissa, and its result would then be
// rounded a second time to double). Each conversion also says whether it was
// exact; on this data set all of them are (every denominator is a power of
// two and every numerator has at most 53 bits), so the doubles are the exact
// query and a reference computed from them is the exact one.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace bfemp::ccd_queries {

// Non-negative big integer, base 2^32 limbs, little-endian, no leading zeros.
class BigUint {
 public:
  BigUint() = default;
  explicit BigUint(const std::string& digits) {
    for (char c : digits) {
      if (c < '0' || c > '9') throw std::invalid_argument("not a decimal integer: '" + digits + "'");
      mul_add(10, static_cast<uint32_t>(c - '0'));
    }
  }
  bool is_zero() const { return limbs_.empty(); }
  int bit_length() const {
    if (limbs_.empty()) return 0;
    int b = 32 * static_cast<int>(limbs_.size() - 1);
    for (uint32_t top = limbs_.back(); top; top >>= 1) ++b;
    return b;
  }
  void shift_left(int bits) {
    if (bits <= 0 || limbs_.empty()) return;
    const int words = bits / 32, rem = bits % 32;
    limbs_.insert(limbs_.begin(), words, 0u);
    if (rem) {
      uint32_t carry = 0;
      for (auto& l : limbs_) {
        const uint32_t next = l >> (32 - rem);
        l = (l << rem) | carry;
        carry = next;
      }
      if (carry) limbs_.push_back(carry);
    }
  }
  friend int compare(const BigUint& a, const BigUint& b) {
    if (a.limbs_.size() != b.limbs_.size()) return a.limbs_.size() < b.limbs_.size() ? -1 : 1;
    for (std::size_t i = a.limbs_.size(); i-- > 0;)
      if (a.limbs_[i] != b.limbs_[i]) return a.limbs_[i] < b.limbs_[i] ? -1 : 1;
    return 0;
  }
  // *this -= b, requires *this >= b.
  void subtract(const BigUint& b) {
    int64_t borrow = 0;
    for (std::size_t i = 0; i < limbs_.size(); ++i) {
      int64_t v = static_cast<int64_t>(limbs_[i]) - borrow - (i < b.limbs_.size() ? b.limbs_[i] : 0);
      borrow = v < 0;
      if (v < 0) v += (int64_t{1} << 32);
      limbs_[i] = static_cast<uint32_t>(v);
    }
    trim();
  }

 private:
  void mul_add(uint32_t m, uint32_t a) {
    uint64_t carry = a;
    for (auto& l : limbs_) {
      const uint64_t v = static_cast<uint64_t>(l) * m + carry;
      l = static_cast<uint32_t>(v);
      carry = v >> 32;
    }
    if (carry) limbs_.push_back(static_cast<uint32_t>(carry));
  }
  void trim() {
    while (!limbs_.empty() && limbs_.back() == 0) limbs_.pop_back();
  }
  std::vector<uint32_t> limbs_;
};

// Nearest double to num / den (decimal strings, num may start with '-'),
// ties to even; `exact` tells whether the double equals the rational.
// Normal range only (the data has no subnormal or overflowing value).
inline double rational_to_double(const std::string& num, const std::string& den, bool* exact = nullptr) {
  const bool neg = !num.empty() && num[0] == '-';
  BigUint n(neg ? num.substr(1) : num), d(den);
  if (d.is_zero()) throw std::invalid_argument("zero denominator in " + num + "/" + den);
  if (n.is_zero()) {
    if (exact) *exact = true;
    return neg ? -0.0 : 0.0;
  }
  // Scale to 1 <= n / d < 2, value = (n / d) * 2^e.
  int e = n.bit_length() - d.bit_length();
  if (e >= 0) d.shift_left(e);
  else n.shift_left(-e);
  if (compare(n, d) < 0) {
    n.shift_left(1);
    --e;
  }
  // 54 quotient bits (53 significant + the rounding bit), remainder sticky.
  uint64_t q = 0;
  for (int i = 0; i < 54; ++i) {
    q <<= 1;
    if (compare(n, d) >= 0) {
      n.subtract(d);
      q |= 1;
    }
    n.shift_left(1);
  }
  const bool sticky = !n.is_zero();
  const bool round_bit = q & 1;
  uint64_t m = q >> 1;  // 53 bits, leading 1
  if (round_bit && (sticky || (m & 1))) ++m;
  if (exact) *exact = !round_bit && !sticky;
  if (e < -1022 || e > 1023) throw std::out_of_range("value out of the normal double range: " + num + "/" + den);
  const double v = std::ldexp(static_cast<double>(m), e - 52);  // m <= 2^53: exact
  return neg ? -v : v;
}

struct Query {
  std::array<std::array<double, 3>, 4> x0, x1;  // point, triangle vertices at t = 0 and t = 1
  int truth = 0;
  std::string file;
  int index = 0;  // in its file
};

struct QuerySet {
  std::vector<Query> queries;
  std::size_t inexact_conversions = 0;
  std::size_t files = 0;
};

// Every */vertex-face/*.csv under dir (sorted); throws on a malformed file.
inline QuerySet load_vertex_face_queries(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().extension() == ".csv" &&
        entry.path().parent_path().filename() == "vertex-face")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  QuerySet set;
  set.files = files.size();
  for (const auto& f : files) {
    std::ifstream in(f);
    if (!in) throw std::runtime_error("cannot read " + f.string());
    const std::string rel = fs::relative(f, dir).string();
    std::string line;
    int row = 0;
    Query q;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty()) continue;
      std::vector<std::string> cells;
      std::stringstream ss(line);
      std::string cell;
      while (std::getline(ss, cell, ',')) cells.push_back(cell);
      if (cells.size() != 7)
        throw std::runtime_error(rel + ": row " + std::to_string(row + 1) + " has " + std::to_string(cells.size()) +
                                 " columns, expected 7");
      const int r = row % 8;
      auto& v = r < 4 ? q.x0[r] : q.x1[r - 4];
      for (int c = 0; c < 3; ++c) {
        bool exact = true;
        v[c] = rational_to_double(cells[2 * c], cells[2 * c + 1], &exact);
        set.inexact_conversions += !exact;
      }
      const int truth = std::stoi(cells[6]);
      if (truth != 0 && truth != 1) throw std::runtime_error(rel + ": ground truth " + cells[6] + " is not 0 or 1");
      if (r == 0) {
        q.truth = truth;
        q.file = rel;
        q.index = row / 8;
      } else if (truth != q.truth) {
        throw std::runtime_error(rel + ": query " + std::to_string(row / 8) + " has mixed ground truths");
      }
      if (r == 7) set.queries.push_back(q);
      ++row;
    }
    if (row % 8 != 0) throw std::runtime_error(rel + ": " + std::to_string(row) + " rows, not a multiple of 8");
  }
  return set;
}

}  // namespace bfemp::ccd_queries
