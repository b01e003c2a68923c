#pragma once
// Probes: named observables of a run, each a number read from its RunTable
// (diagnostics.csv, or the same columns recorded in memory). The scene
// tests, scripts/validate.sh (through `bfemp probe`) and `bfemp sweep` all
// measure runs with these, so a figure in the validation report is the figure
// a test asserts.
//
// A probe is named by a spec "name:key=value,key=value" (`bfemp sweep --help`
// lists them). Times are in s; "from"/"to" select the rows with from <= t <=
// to (defaults: the whole run); "t" picks the row nearest that time (default:
// the last row). Axes are x, y, z.
//
//  com, velocity      centre of mass of a body, and its velocity (m, m/s)
//  acceleration       2 c2 of the least-squares fit com = c0 + c1 t + c2 t^2
//                     over [from, to] (m/s^2)
//  max_speed          max |velocity component| of a body over [from, to]
//  contact_start/end  first / last time with contact pairs (NaN: none)
//  energy_lost_pct    100 (E(from) - E(to)) / E(from) of total_energy; the
//                     defaults are the row before contact and the first row
//                     after it (the loss during contact, VALIDATION A1)
//  momentum_drift     max |p_axis(t) - p_axis(0)| over the run, divided by
//                     |p| of body `relative_to` at t = 0 when given
//  contact_force      component of the contact force on the reported FEM
//                     body (Contact/force body) at t (N; N/m in 2D)
//  half_width         half the extent along `axis` of the particles in
//                     contact with that body at t (the Hertz a of A3)
//  hertz_slope        least-squares slope k of F = k a^2 + c over the contact
//                     rows with a <= a_max (F: contact_force `force_axis`,
//                     sign so that F > 0; a: half_width along `axis`)
//  equilibrium_height mass-weighted centre-of-mass `axis` of the bodies
//                     listed in `bodies` (joined by '+') at t (A5)
//  min, max, sum, value of any diagnostics column over [from, to] (value: at t)
//  rotation           mean rotation angle (rad) about `axis` through `center`
//                     of the particles inside [box_min, box_max] at frame 0,
//                     at the output frame nearest t (read from the run's
//                     bfemp.h5; vectors are written x;y[;z]); A7's twist
//  peak_rotation      rotation's value of largest magnitude over the frames
//                     (rad): A7's slip angle
//  lead_onset         first frame time at which the particles inside
//                     [box_min, box_max] at frame 0 lead a motion at `speed`
//                     along `axis` (a driven plate: travel = speed t) by more
//                     than `threshold`: lead = sign(speed) (mean u_axis -
//                     speed t) (m); NaN: never. A6's buckling onset (the
//                     inner ring's crown falls away from the plate)
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "probes/run_table.hpp"

namespace bfemp {

struct ProbeArgs {
  std::string name;
  std::map<std::string, std::string> values;
  // "name:key=value,key=value"; std::invalid_argument naming the spec.
  static ProbeArgs parse(const std::string& spec);
  bool has(const std::string& key) const { return values.count(key) > 0; }
  std::string text(const std::string& key) const;  // required
  std::string text(const std::string& key, const std::string& fallback) const;
  double number(const std::string& key) const;  // required
  double number(const std::string& key, double fallback) const;
  int axis(const std::string& key = "axis", int fallback = 0) const;  // x, y, z -> 0, 1, 2
};

struct ProbeInfo {
  std::string name, args, help;
  std::function<double(const RunTable&, const ProbeArgs&)> eval;
};

// Every probe, in the order of the header comment.
const std::vector<ProbeInfo>& probe_list();
// Evaluates "name:args" on the table; std::invalid_argument naming the probe,
// the key and what was expected for an unknown name or bad argument.
double evaluate_probe(const std::string& spec, const RunTable& t);
// The probe a spec names, its keys checked (the same errors, without a run).
const ProbeInfo& check_probe_spec(const std::string& spec);

// The probes as functions, for tests.
namespace probe {
std::size_t row_at(const RunTable& t, double time);  // nearest row
double com(const RunTable& t, const std::string& body, int axis, double time);
double velocity(const RunTable& t, const std::string& body, int axis, double time);
double acceleration(const RunTable& t, const std::string& body, int axis, double from, double to);
double max_speed(const RunTable& t, const std::string& body, int axis, double from, double to);
double contact_start(const RunTable& t);
double contact_end(const RunTable& t);
double energy_lost_pct(const RunTable& t, double from, double to);
double energy_lost_during_contact_pct(const RunTable& t);
double momentum_drift(const RunTable& t, int axis);
double half_width(const RunTable& t, int axis, std::size_t row);
// Least-squares slope of y against x (with intercept); NaN for < 2 points.
double fit_slope(const std::vector<double>& x, const std::vector<double>& y);
double hertz_slope(const RunTable& t, int force_axis, int width_axis, double a_max);
double equilibrium_height(const RunTable& t, const std::vector<std::string>& bodies, int axis, double time);
// Mean angle of rotation about the axis (0, 1, 2; 2D: 2 only) through
// `center` from frame 0 to the frame nearest `time` (NaN: the last), of the
// particles inside [lo, hi] at frame 0, each angle in (-pi, pi]; `h5` is a
// run's bfemp.h5. std::invalid_argument when no particle is selected.
double rotation(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi,
                const std::vector<double>& center, int axis, double time);
// The value of rotation() of largest magnitude over all frames (signed):
// how far the point set turned before it slipped back (A7's slip angle).
double peak_rotation(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi,
                     const std::vector<double>& center, int axis);
// Time of the first frame whose particles selected in [lo, hi] at frame 0
// lead the travel speed * t along `axis` by more than `threshold` (above);
// NaN when no frame does. std::invalid_argument when none is selected or
// speed is 0.
double lead_onset(const std::string& h5, const std::vector<double>& lo, const std::vector<double>& hi, int axis,
                  double speed, double threshold);
}  // namespace probe

}  // namespace bfemp
