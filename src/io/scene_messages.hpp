#pragma once
// The wording of scene refusals, shared by the scene loader and its checks:
//   scene key '<path>' = <value>: expected <what>
#include <Teuchos_Array.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

namespace bfemp::scene_msg {

[[noreturn]] inline void bad(const std::string& key, const std::string& value, const std::string& expected) {
  throw std::invalid_argument("scene key '" + key + "' = " + value + ": expected " + expected);
}

inline std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

inline std::string list(const Teuchos::Array<double>& a) {
  std::string s = "[";
  for (Teuchos::Array<double>::size_type i = 0; i < a.size(); ++i) s += (i ? ", " : "") + num(a[i]);
  return s + "]";
}

// `t` without leading and trailing spaces.
inline std::string trim(const std::string& t) {
  const auto a = t.find_first_not_of(' '), b = t.find_last_not_of(' ');
  return a == std::string::npos ? "" : t.substr(a, b - a + 1);
}

}  // namespace bfemp::scene_msg
