#include "probes/probes.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "io/hdf5_frames.hpp"

namespace bfemp {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
const char* kAxis[] = {"x", "y", "z"};

[[noreturn]] void bad_arg(const std::string& probe, const std::string& key, const std::string& value,
                          const std::string& expected) {
  throw std::invalid_argument("probe '" + probe + "': " + key + " = '" + value + "', expected " + expected);
}

const std::vector<double>& body_column(const RunTable& t, const std::string& body, const std::string& field) {
  const std::string name = body + "." + field;
  if (!t.has(name)) {
    std::string list;
    for (const auto& b : t.bodies()) list += (list.empty() ? "" : ", ") + b;
    throw std::invalid_argument("probe: no body '" + body + "' in this run (bodies: " + list + ")");
  }
  return t.column(name);
}

// Rows with from <= time <= to.
std::vector<std::size_t> rows_in(const RunTable& t, double from, double to) {
  const auto& time = t.column("time");
  std::vector<std::size_t> r;
  for (std::size_t i = 0; i < time.size(); ++i)
    if (time[i] >= from && time[i] <= to) r.push_back(i);
  return r;
}

}  // namespace

// ---- ProbeArgs ---------------------------------------------------------------

ProbeArgs ProbeArgs::parse(const std::string& spec) {
  ProbeArgs a;
  const auto colon = spec.find(':');
  a.name = spec.substr(0, colon);
  if (a.name.empty()) throw std::invalid_argument("probe spec '" + spec + "': no probe name before ':'");
  if (colon == std::string::npos) return a;
  std::stringstream ss(spec.substr(colon + 1));
  std::string kv;
  while (std::getline(ss, kv, ',')) {
    if (kv.empty()) continue;
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("probe spec '" + spec + "': '" + kv + "' is not key=value");
    a.values[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  return a;
}

std::string ProbeArgs::text(const std::string& key) const {
  const auto it = values.find(key);
  if (it == values.end()) bad_arg(name, key, "", "a value (required argument)");
  return it->second;
}

std::string ProbeArgs::text(const std::string& key, const std::string& fallback) const {
  const auto it = values.find(key);
  return it == values.end() ? fallback : it->second;
}

double ProbeArgs::number(const std::string& key) const {
  const std::string s = text(key);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0') bad_arg(name, key, s, "a number");
  return v;
}

double ProbeArgs::number(const std::string& key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

int ProbeArgs::axis(const std::string& key, int fallback) const {
  if (!has(key)) return fallback;
  const std::string s = text(key);
  for (int c = 0; c < 3; ++c)
    if (s == kAxis[c]) return c;
  bad_arg(name, key, s, "x, y or z");
}

// ---- probe functions ---------------------------------------------------------

namespace probe {

std::size_t row_at(const RunTable& t, double time) {
  const auto& tt = t.column("time");
  if (tt.empty()) throw std::invalid_argument("probe: the run has no rows");
  if (!std::isfinite(time)) return tt.size() - 1;
  std::size_t best = 0;
  for (std::size_t i = 1; i < tt.size(); ++i)
    if (std::abs(tt[i] - time) < std::abs(tt[best] - time)) best = i;
  return best;
}

double com(const RunTable& t, const std::string& body, int axis, double time) {
  return body_column(t, body, std::string("com_") + kAxis[axis])[row_at(t, time)];
}

double velocity(const RunTable& t, const std::string& body, int axis, double time) {
  return body_column(t, body, std::string("vel_") + kAxis[axis])[row_at(t, time)];
}

double acceleration(const RunTable& t, const std::string& body, int axis, double from, double to) {
  const auto& x = body_column(t, body, std::string("com_") + kAxis[axis]);
  const auto& time = t.column("time");
  const auto rows = rows_in(t, from, to);
  if (rows.size() < 3) return kNaN;
  double tm = 0;
  for (auto i : rows) tm += time[i];
  tm /= double(rows.size());
  // Scaled time s = (t - tm) / T keeps the normal equations well conditioned.
  const double T = std::max(time[rows.back()] - tm, tm - time[rows.front()]);
  if (!(T > 0)) return kNaN;
  double S[5] = {0, 0, 0, 0, 0}, B[3] = {0, 0, 0};
  const double x0 = x[rows.front()];
  for (auto i : rows) {
    const double s = (time[i] - tm) / T, y = x[i] - x0;
    double sk = 1;
    for (int k = 0; k < 5; ++k) {
      S[k] += sk;
      if (k < 3) B[k] += sk * y;
      sk *= s;
    }
  }
  auto det3 = [](double a, double b, double c, double d, double e, double f, double g, double h, double i) {
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
  };
  const double D = det3(S[0], S[1], S[2], S[1], S[2], S[3], S[2], S[3], S[4]);
  const double D2 = det3(S[0], S[1], B[0], S[1], S[2], B[1], S[2], S[3], B[2]);
  return 2 * (D2 / D) / (T * T);
}

double max_speed(const RunTable& t, const std::string& body, int axis, double from, double to) {
  const auto& v = body_column(t, body, std::string("vel_") + kAxis[axis]);
  double m = 0;
  for (auto i : rows_in(t, from, to)) m = std::max(m, std::abs(v[i]));
  return m;
}

double contact_start(const RunTable& t) {
  const auto& pairs = t.column("contact_pairs");
  const auto& time = t.column("time");
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i] > 0) return time[i];
  return kNaN;
}

double contact_end(const RunTable& t) {
  const auto& pairs = t.column("contact_pairs");
  const auto& time = t.column("time");
  for (std::size_t i = pairs.size(); i-- > 0;)
    if (pairs[i] > 0) return time[i];
  return kNaN;
}

double energy_lost_pct(const RunTable& t, double from, double to) {
  const auto& e = t.column("total_energy");
  const double e0 = e[row_at(t, from)], e1 = e[row_at(t, to)];
  return 100.0 * (e0 - e1) / e0;
}

double energy_lost_during_contact_pct(const RunTable& t) {
  const auto& pairs = t.column("contact_pairs");
  const auto& e = t.column("total_energy");
  std::size_t first = pairs.size(), last = pairs.size();
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i] > 0) {
      if (first == pairs.size()) first = i;
      last = i;
    }
  if (first == pairs.size() || last + 1 >= pairs.size()) return kNaN;  // no contact, or not separated yet
  const std::size_t before = first > 0 ? first - 1 : 0;
  return 100.0 * (e[before] - e[last + 1]) / e[before];
}

double momentum_drift(const RunTable& t, int axis) {
  const auto& p = t.column(std::string("momentum_") + kAxis[axis]);
  double d = 0;
  for (double v : p) d = std::max(d, std::abs(v - p.front()));
  return d;
}

double half_width(const RunTable& t, int axis, std::size_t row) {
  const auto& lo = t.column(std::string("contact_lo_") + kAxis[axis]);
  const auto& hi = t.column(std::string("contact_hi_") + kAxis[axis]);
  return 0.5 * (hi[row] - lo[row]);  // NaN without contact
}

double fit_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 2 || y.size() != n) return kNaN;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= double(n);
  my /= double(n);
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < n; ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxx > 0 ? sxy / sxx : kNaN;
}

double hertz_slope(const RunTable& t, int force_axis, int width_axis, double a_max) {
  const auto& f = t.column(std::string("contact_force_") + kAxis[force_axis]);
  std::vector<double> a2, F;
  double sign = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    const double a = half_width(t, width_axis, i);
    if (!(a > 0) || a > a_max) continue;
    if (sign == 0 && f[i] != 0) sign = f[i] > 0 ? 1 : -1;
    a2.push_back(a * a);
    F.push_back(f[i]);
  }
  for (double& v : F) v *= sign == 0 ? 1 : sign;
  return fit_slope(a2, F);
}

double equilibrium_height(const RunTable& t, const std::vector<std::string>& bodies, int axis, double time) {
  const std::size_t row = row_at(t, time);
  double M = 0, mx = 0;
  for (const auto& b : bodies) {
    const double m = body_column(t, b, "mass")[row];
    M += m;
    mx += m * body_column(t, b, std::string("com_") + kAxis[axis])[row];
  }
  return M > 0 ? mx / M : kNaN;
}

namespace {

std::string frame_group(int k) {
  char b[32];
  std::snprintf(b, sizeof b, "/frame_%06d", k);
  return std::string(b);
}

// Number of frames with particle positions in a run's bfemp.h5 (> 0).
int particle_frames(const std::string& h5, const std::string& probe) {
  int frames = 0;
  while (dataset_exists(h5, frame_group(frames) + "/particle_positions")) ++frames;
  if (frames == 0) throw std::invalid_argument("probe " + probe + ": no particle frames in '" + h5 + "'");
  return frames;
}

// Particles inside [lo, hi] (x, dim components each) at frame 0.
std::vector<std::size_t> particles_in_box(const std::vector<double>& x0, std::size_t dim, const std::vector<double>& lo,
                                          const std::vector<double>& hi) {
  std::vector<std::size_t> sel;
  for (std::size_t q = 0; q < x0.size() / dim; ++q) {
    bool in = true;
    for (std::size_t c = 0; c < dim; ++c) in = in && x0[q * dim + c] >= lo[c] && x0[q * dim + c] <= hi[c];
    if (in) sel.push_back(q);
  }
  return sel;
}

}  // namespace

namespace {

// Mean rotation about `axis` through `center` from frame 0 to each frame in
// `picks`, of the particles in [lo, hi] at frame 0 (see probe::rotation).
std::vector<double> rotations(const std::string& h5, const std::string& probe, const std::vector<double>& lo,
                              const std::vector<double>& hi, const std::vector<double>& center, int axis,
                              const std::vector<int>& picks) {
  std::vector<std::size_t> shape;
  const std::vector<double> x0 = read_dataset(h5, frame_group(0) + "/particle_positions", &shape);
  const std::size_t dim = shape.size() > 1 ? shape[1] : 1;
  if (lo.size() != dim || hi.size() != dim || center.size() != dim)
    throw std::invalid_argument("probe " + probe + ": box_min, box_max and center need " + std::to_string(dim) +
                                " components (x;y" + std::string(dim == 3 ? ";z" : "") + ")");
  if (dim == 2 && axis != 2) throw std::invalid_argument("probe " + probe + ": 2D rotates about z only (axis=z)");
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;  // the plane of the rotation
  std::vector<std::size_t> sel;
  for (const std::size_t q : particles_in_box(x0, dim, lo, hi)) {
    const double a0 = x0[q * dim + i] - center[i], b0 = x0[q * dim + j] - center[j];
    if (a0 * a0 + b0 * b0 >= 1e-24) sel.push_back(q);  // on the axis: no angle
  }
  if (sel.empty())
    throw std::invalid_argument("probe " + probe + ": no particle inside [box_min, box_max] off the axis at frame 0");
  std::vector<double> out;
  for (const int k : picks) {
    const std::vector<double> x1 =
        k == 0 ? x0 : read_dataset(h5, frame_group(k) + "/particle_positions", nullptr);
    double sum = 0;
    for (const std::size_t q : sel) {
      const double a0 = x0[q * dim + i] - center[i], b0 = x0[q * dim + j] - center[j];
      const double a1 = x1[q * dim + i] - center[i], b1 = x1[q * dim + j] - center[j];
      sum += std::atan2(a0 * b1 - b0 * a1, a0 * a1 + b0 * b1);
    }
    out.push_back(sum / double(sel.size()));
  }
  return out;
}

}  // namespace

double rotation(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi,
                const std::vector<double>& center, int axis, double time) {
  const int frames = particle_frames(h5, "rotation");
  int pick = frames - 1;
  if (std::isfinite(time)) {
    double best = kInf;
    for (int k = 0; k < frames; ++k) {
      const double d = std::abs(read_attribute(h5, frame_group(k), "time") - time);
      if (d < best) best = d, pick = k;
    }
  }
  return rotations(h5, "rotation", lo, hi, center, axis, {pick})[0];
}

double peak_rotation(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi,
                     const std::vector<double>& center, int axis) {
  const int frames = particle_frames(h5, "peak_rotation");
  std::vector<int> all(frames);
  for (int k = 0; k < frames; ++k) all[k] = k;
  double peak = 0;
  for (const double r : rotations(h5, "peak_rotation", lo, hi, center, axis, all))
    if (std::abs(r) > std::abs(peak)) peak = r;
  return peak;
}

double lead_onset(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi, int axis,
                  double speed, double threshold) {
  auto num = [](double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  };
  if (!(speed != 0) || !std::isfinite(speed))
    throw std::invalid_argument("probe lead_onset: speed = " + num(speed) + ", expected a nonzero number");
  if (!(threshold > 0) || !std::isfinite(threshold))
    throw std::invalid_argument("probe lead_onset: threshold = " + num(threshold) + ", expected a number > 0 (m)");
  const int frames = particle_frames(h5, "lead_onset");
  std::vector<std::size_t> shape0;
  const std::vector<double> x0 = read_dataset(h5, frame_group(0) + "/particle_positions", &shape0);
  const std::size_t dim = shape0.size() > 1 ? shape0[1] : 1;
  if (lo.size() != dim || hi.size() != dim)
    throw std::invalid_argument("probe lead_onset: box_min and box_max have " + std::to_string(lo.size()) + " and " +
                                std::to_string(hi.size()) + " components, expected " + std::to_string(dim) + " (x;y" +
                                std::string(dim == 3 ? ";z" : "") + ")");
  if (axis >= int(dim))
    throw std::invalid_argument("probe lead_onset: axis = z, expected x or y in a 2D run");
  const std::vector<std::size_t> sel = particles_in_box(x0, dim, lo, hi);
  if (sel.empty()) throw std::invalid_argument("probe lead_onset: no particle inside [box_min, box_max] at frame 0");
  const double sign = speed > 0 ? 1.0 : -1.0;
  const double t0 = read_attribute(h5, frame_group(0), "time");  // a restarted run's frame 0 is its checkpoint's
  for (int k = 1; k < frames; ++k) {
    std::vector<std::size_t> shape;
    const std::vector<double> x = read_dataset(h5, frame_group(k) + "/particle_positions", &shape);
    if (shape != shape0)
      throw std::invalid_argument("probe lead_onset: frame " + std::to_string(k) + " has another particle count than frame 0");
    double u = 0;
    for (const std::size_t q : sel) u += x[q * dim + axis] - x0[q * dim + axis];
    u /= double(sel.size());
    const double t = read_attribute(h5, frame_group(k), "time");
    if (sign * (u - speed * (t - t0)) > threshold) return t;
  }
  return kNaN;
}

}  // namespace probe

// ---- the registry ------------------------------------------------------------

namespace {

double from_of(const ProbeArgs& a) { return a.number("from", -kInf); }

// A vector argument "x;y[;z]".
std::vector<double> vector_arg(const ProbeArgs& a, const std::string& key) {
  std::vector<double> v;
  std::stringstream ss(a.text(key));
  std::string item;
  while (std::getline(ss, item, ';')) {
    char* end = nullptr;
    v.push_back(std::strtod(item.c_str(), &end));
    if (end == item.c_str() || *end != '\0') bad_arg(a.name, key, a.text(key), "numbers joined by ';'");
  }
  return v;
}

// The run's bfemp.h5, for probes that read its frames.
std::string frames_file(const RunTable& t, const ProbeArgs& a) {
  if (t.source_dir().empty())
    throw std::invalid_argument("probe '" + a.name + "' reads a run's frames: evaluate it on a run directory");
  return t.source_dir() + "/bfemp.h5";
}
double to_of(const ProbeArgs& a) { return a.number("to", kInf); }
double t_of(const ProbeArgs& a) { return a.number("t", kNaN); }

std::vector<std::string> split_plus(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string b;
  while (std::getline(ss, b, '+'))
    if (!b.empty()) out.push_back(b);
  return out;
}

template <class F>
double column_reduce(const RunTable& t, const ProbeArgs& a, double init, F op) {
  const auto& c = t.column(a.text("column"));
  double acc = init;
  for (auto i : rows_in(t, from_of(a), to_of(a))) acc = op(acc, c[i]);
  return acc;
}

}  // namespace

const std::vector<ProbeInfo>& probe_list() {
  static const std::vector<ProbeInfo> list = {
      {"com", "body=NAME[,axis=x][,t=T]", "centre of mass of a body at t (m)",
       [](const RunTable& t, const ProbeArgs& a) { return probe::com(t, a.text("body"), a.axis(), t_of(a)); }},
      {"velocity", "body=NAME[,axis=x][,t=T]", "centre-of-mass velocity of a body at t (m/s)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::velocity(t, a.text("body"), a.axis(), t_of(a));
       }},
      {"acceleration", "body=NAME[,axis=x][,from=T0][,to=T1]",
       "centre-of-mass acceleration, least-squares quadratic fit over [from, to] (m/s^2)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::acceleration(t, a.text("body"), a.axis(), from_of(a), to_of(a));
       }},
      {"max_speed", "body=NAME[,axis=x][,from=T0][,to=T1]", "max |centre-of-mass velocity| (m/s)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::max_speed(t, a.text("body"), a.axis(), from_of(a), to_of(a));
       }},
      {"contact_start", "", "first time with contact pairs (s; NaN: none)",
       [](const RunTable& t, const ProbeArgs&) { return probe::contact_start(t); }},
      {"contact_end", "", "last time with contact pairs (s; NaN: none)",
       [](const RunTable& t, const ProbeArgs&) { return probe::contact_end(t); }},
      {"energy_lost_pct", "[from=T0,to=T1]",
       "total energy lost, % of E(from); default: during contact (row before the first pair to the first row "
       "after the last)",
       [](const RunTable& t, const ProbeArgs& a) {
         if (!a.has("from") && !a.has("to")) return probe::energy_lost_during_contact_pct(t);
         return probe::energy_lost_pct(t, a.number("from", 0.0), a.number("to", kNaN));
       }},
      {"momentum_drift", "[axis=x][,relative_to=BODY]",
       "max |p(t) - p(0)| along axis, over |p| of BODY at t = 0 when given",
       [](const RunTable& t, const ProbeArgs& a) {
         const double d = probe::momentum_drift(t, a.axis());
         if (!a.has("relative_to")) return d;
         const std::string b = a.text("relative_to");
         double v2 = 0;
         for (int c = 0; c < 3; ++c) v2 += std::pow(body_column(t, b, std::string("vel_") + kAxis[c])[0], 2);
         return d / (body_column(t, b, "mass")[0] * std::sqrt(v2));
       }},
      {"contact_force", "[axis=y][,t=T]", "contact force on the reported FEM body at t (N, N/m in 2D)",
       [](const RunTable& t, const ProbeArgs& a) {
         return t.column(std::string("contact_force_") + kAxis[a.axis("axis", 1)])[probe::row_at(t, t_of(a))];
       }},
      {"half_width", "[axis=x][,t=T]", "half the extent of the particles in contact with that body (m)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::half_width(t, a.axis(), probe::row_at(t, t_of(a)));
       }},
      {"hertz_slope", "[force_axis=y][,axis=x][,a_max=A]",
       "least-squares slope of contact force against half_width^2 over rows with a <= a_max (N/m^2)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::hertz_slope(t, a.axis("force_axis", 1), a.axis(), a.number("a_max", kInf));
       }},
      {"equilibrium_height", "bodies=A+B[,axis=y][,t=T]", "mass-weighted centre of mass of the bodies at t (m)",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::equilibrium_height(t, split_plus(a.text("bodies")), a.axis("axis", 1), t_of(a));
       }},
      {"min", "column=NAME[,from=T0][,to=T1]", "smallest value of a diagnostics column",
       [](const RunTable& t, const ProbeArgs& a) {
         return column_reduce(t, a, kInf, [](double s, double v) { return std::min(s, v); });
       }},
      {"max", "column=NAME[,from=T0][,to=T1]", "largest value of a diagnostics column",
       [](const RunTable& t, const ProbeArgs& a) {
         return column_reduce(t, a, -kInf, [](double s, double v) { return std::max(s, v); });
       }},
      {"sum", "column=NAME[,from=T0][,to=T1]", "sum of a diagnostics column (e.g. newton_iters, step_s)",
       [](const RunTable& t, const ProbeArgs& a) {
         return column_reduce(t, a, 0.0, [](double s, double v) { return s + v; });
       }},
      {"rotation", "box_min=X;Y[;Z],box_max=X;Y[;Z],center=X;Y[;Z][,axis=z][,t=T]",
       "mean rotation angle about the axis of the particles in the box at frame 0, at the frame nearest t "
       "(rad; reads the run's bfemp.h5)",
       [](const RunTable& t, const ProbeArgs& a) {
         auto vec = [&](const std::string& key) { return vector_arg(a, key); };
         return probe::rotation(frames_file(t, a), vec("box_min"), vec("box_max"), vec("center"), a.axis("axis", 2),
                                t_of(a));
       }},
      {"peak_rotation", "box_min=X;Y[;Z],box_max=X;Y[;Z],center=X;Y[;Z][,axis=z]",
       "the rotation probe's value of largest magnitude over all frames (rad; reads the run's bfemp.h5); A7's "
       "slip angle: the twist the cube's top follows before it slips",
       [](const RunTable& t, const ProbeArgs& a) {
         auto vec = [&](const std::string& key) { return vector_arg(a, key); };
         return probe::peak_rotation(frames_file(t, a), vec("box_min"), vec("box_max"), vec("center"),
                                     a.axis("axis", 2));
       }},
      {"lead_onset", "box_min=X;Y[;Z],box_max=X;Y[;Z],speed=V[,axis=y][,threshold=D]",
       "first frame time at which the particles in the box at frame 0 lead a travel speed*t along the axis by "
       "more than D (default 0.15 m) (s; NaN: never; reads the run's bfemp.h5); A6's buckling onset",
       [](const RunTable& t, const ProbeArgs& a) {
         return probe::lead_onset(frames_file(t, a), vector_arg(a, "box_min"), vector_arg(a, "box_max"),
                                  a.axis("axis", 1), a.number("speed"), a.number("threshold", 0.15));
       }},
      {"value", "column=NAME[,t=T]", "a diagnostics column at t",
       [](const RunTable& t, const ProbeArgs& a) { return t.column(a.text("column"))[probe::row_at(t, t_of(a))]; }},
  };
  return list;
}

const ProbeInfo& check_probe_spec(const std::string& spec) {
  const ProbeArgs a = ProbeArgs::parse(spec);
  for (const auto& p : probe_list()) {
    if (p.name != a.name) continue;
    std::vector<std::string> keys;  // the identifiers before each '=' of p.args
    for (std::size_t e = p.args.find('='); e != std::string::npos; e = p.args.find('=', e + 1)) {
      std::size_t b = e;
      while (b > 0 && (std::isalnum(static_cast<unsigned char>(p.args[b - 1])) || p.args[b - 1] == '_')) --b;
      keys.push_back(p.args.substr(b, e - b));
    }
    for (const auto& kv : a.values) {  // a misspelled key is refused, not ignored
      if (std::find(keys.begin(), keys.end(), kv.first) == keys.end())
        bad_arg(p.name, kv.first, kv.second, "one of the keys " + (p.args.empty() ? "(none)" : p.args));
    }
    return p;
  }
  std::string names;
  for (const auto& p : probe_list()) names += (names.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument("probe '" + a.name + "' unknown (probes: " + names + ")");
}

double evaluate_probe(const std::string& spec, const RunTable& t) {
  return check_probe_spec(spec).eval(t, ProbeArgs::parse(spec));
}

}  // namespace bfemp
