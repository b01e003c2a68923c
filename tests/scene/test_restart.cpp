// Restart and interruption, through the real executable (1 OpenMP thread):
//  - N steps + `bfemp restart` + N steps equals 2N uninterrupted steps
//    bit-for-bit (every checkpointed field, every diagnostics value but the
//    timings) for an FEM scene, an MPM scene whose grid extends before and
//    after the restart, and a contact scene with friction (backward Euler and
//    Newmark); the same into a new directory (--output);
//  - SIGTERM / SIGINT mid-run: exit 143 / 130, a checkpoint, a line naming the
//    restart command, and the restarted run equals the uninterrupted one;
//  - SIGKILL mid-run: every frame the XDMF lists is readable with the sizes
//    it states, and the restart from the last periodic checkpoint drops the
//    later frames and rows and still equals the uninterrupted run;
//  - restart --set of a key that changes the state is refused (exit 2);
//  - a solver failure checkpoints the last completed step (exit 3), and the
//    restart with a higher Newton cap equals the run that had it throughout;
//  - the explicit stepper (Solver: explicit, B1 blocks in contact under the
//    piston, LR normals, XPIC(5)): the same bit-for-bit continuation, and
//    SIGTERM mid-run; its frames are listed in bfemp.xdmf.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/hdf5_frames.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
const std::string exe = std::string(BFEMP_BINARY_DIR) + "/drivers/bfemp";
const std::string root = std::string(BFEMP_BINARY_DIR) + "/test_runs/restart";
const std::string src = BFEMP_SOURCE_DIR;

std::string dir_of(const std::string& tag) { return root + "/" + tag; }

// Runs bfemp with `args` (already quoted); returns the exit status.
int run_bfemp(const std::string& args, const std::string& log) {
  fs::create_directories(root);
  const std::string cmd = "OMP_NUM_THREADS=1 OMP_PROC_BIND=false OPENBLAS_NUM_THREADS=1 " + exe + " " + args + " > " +
                          log + " 2>&1";
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : 1000 + st;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string fresh(const std::string& tag) {
  fs::remove_all(dir_of(tag));
  return dir_of(tag);
}

// Every field, attribute and the resolved scene equal bit for bit.
void expect_same_checkpoint(const std::string& a, const std::string& b) {
  const bfemp::Checkpoint ca = bfemp::read_checkpoint(a + "/checkpoint.h5");
  const bfemp::Checkpoint cb = bfemp::read_checkpoint(b + "/checkpoint.h5");
  EXPECT_EQ(ca.step, cb.step);
  EXPECT_EQ(std::memcmp(&ca.time, &cb.time, sizeof(double)), 0) << ca.time << " vs " << cb.time;
  ASSERT_EQ(ca.arrays.size(), cb.arrays.size());
  for (const auto& [name, x] : ca.arrays) {
    ASSERT_TRUE(cb.has(name)) << name;
    const auto& y = cb.arrays.at(name);
    ASSERT_EQ(x.rows, y.rows) << name;
    ASSERT_EQ(x.integer, y.integer) << name;
    if (x.integer) {
      EXPECT_EQ(x.ints, y.ints) << name;
    } else {
      ASSERT_EQ(x.real.size(), y.real.size()) << name;
      std::size_t diff = 0;
      for (std::size_t i = 0; i < x.real.size(); ++i) diff += std::memcmp(&x.real[i], &y.real[i], sizeof(double)) != 0;
      EXPECT_EQ(diff, 0u) << name << ": " << diff << " of " << x.real.size() << " values differ";
    }
  }
}

std::vector<std::vector<std::string>> csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(slurp(path));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> r;
    std::istringstream ls(line);
    for (std::string f; std::getline(ls, f, ',');) r.push_back(f);
    rows.push_back(r);
  }
  return rows;
}

// diagnostics.csv of `b` (a restarted run) equals `a` row for row from step
// `from` on (all of it when from = 1), but for the timing columns.
void expect_same_diagnostics(const std::string& a, const std::string& b, long from = 1) {
  const auto ra = csv(a + "/diagnostics.csv"), rb = csv(b + "/diagnostics.csv");
  ASSERT_FALSE(ra.empty());
  ASSERT_EQ(ra[0], rb[0]) << "headers";
  std::vector<bool> timing(ra[0].size());
  for (std::size_t c = 0; c < ra[0].size(); ++c)
    timing[c] = ra[0][c] == "assembly_s" || ra[0][c] == "solve_s" || ra[0][c] == "step_s";
  std::size_t ia = 1;
  while (ia < ra.size() && std::stol(ra[ia][0]) < from) ++ia;
  ASSERT_EQ(ra.size() - ia, rb.size() - 1) << "rows from step " << from;
  for (std::size_t ib = 1; ib < rb.size(); ++ib, ++ia)
    for (std::size_t c = 0; c < ra[0].size(); ++c)
      if (!timing[c]) {
        EXPECT_EQ(ra[ia][c], rb[ib][c]) << "step " << ra[ia][0] << " column " << ra[0][c];
      }
}

struct Case {
  std::string tag, scene, sets;
  double dt;
  int n;  // steps before the restart; the run goes to 2n
};

std::string end_time(const Case& c, double steps) {
  std::ostringstream s;
  s.precision(17);
  s << "--set 'Time/end time=" << (steps - 0.25) * c.dt << "'";
  return s.str();
}

// Returns the checkpoint after the first n steps.
bfemp::Checkpoint restart_equals_uninterrupted(const Case& c) {
  const std::string full = fresh(c.tag + "_full"), half = fresh(c.tag + "_half"), other = fresh(c.tag + "_other");
  EXPECT_EQ(run_bfemp("run " + c.scene + " " + c.sets + " " + end_time(c, 2 * c.n) + " -o " + full, full + ".log"), 0)
      << slurp(full + ".log");
  EXPECT_EQ(run_bfemp("run " + c.scene + " " + c.sets + " " + end_time(c, c.n) + " -o " + half, half + ".log"), 0)
      << slurp(half + ".log");
  const bfemp::Checkpoint mid = bfemp::read_checkpoint(half + "/checkpoint.h5");
  EXPECT_EQ(mid.step, c.n);
  // Into a new directory first (the checkpoint in `half` stays as it is) ...
  EXPECT_EQ(run_bfemp("restart " + half + " " + end_time(c, 2 * c.n) + " -o " + other, other + ".log"), 0)
      << slurp(other + ".log");
  // ... then appending to the run's own directory.
  EXPECT_EQ(run_bfemp("restart " + half + " " + end_time(c, 2 * c.n), half + ".restart.log"), 0)
      << slurp(half + ".restart.log");
  expect_same_checkpoint(full, half);
  expect_same_checkpoint(full, other);
  expect_same_diagnostics(full, half);
  expect_same_diagnostics(full, other, c.n + 1);
  // The new directory starts at the checkpoint: its frame 0 is step n.
  EXPECT_EQ(bfemp::read_attribute(other + "/bfemp.h5", "/frame_000000", "step"), c.n);
  return mid;
}

const std::string squash = src + "/tests/data/squash_10_steps.yaml";
const std::string disk_wall = src + "/inputs/contact_disk_wall.yaml";
const std::string friction_sets =
    "--set 'Contact/friction=0.3' --set 'MPM Bodies/disk/initial velocity={100.0, 30.0}' "
    "--set 'Output/frame every=3' --set 'Output/progress every=0'";

// A 0.2 m block thrown at 6 m/s out of a 0.5 m grid that extends.
std::string thrown_scene() {
  const std::string path = root + "/thrown.yaml";
  fs::create_directories(root);
  std::ofstream(path) << R"(bfemp:
  dimension: 2
  gravity: [0.0, -9.81]
  Time:
    dt: 1.0e-2
    end time: 0.1
    integrator: newmark
  Output:
    frame every: 4
    progress every: 0
  Materials:
    jelly:
      E: 1.0e5
      nu: 0.3
      density: 1000.0
  MPM:
    grid spacing: 0.05
    domain min: [0.0, 0.0]
    domain max: [0.5, 0.5]
    particles per cell: 4
    transfer: APIC
    when particles leave: extend
  MPM Bodies:
    block:
      material: jelly
      shape: box
      center: [0.25, 0.25]
      size: [0.2, 0.2]
      initial velocity: [6.0, 2.0]
)";
  return path;
}

pid_t spawn(const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> env_s = {"OMP_NUM_THREADS=1", "OMP_PROC_BIND=false", "OPENBLAS_NUM_THREADS=1"};
  // The parent's environment but for those three, as std::system passes it
  // (OPENBLAS_CORETYPE and the like choose BLAS kernels: other round-off).
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "OMP_NUM_THREADS=", 16) && std::strncmp(*e, "OMP_PROC_BIND=", 14) &&
        std::strncmp(*e, "OPENBLAS_NUM_THREADS=", 21))
      env_s.push_back(*e);
  std::vector<char*> argv, envp;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (const auto& e : env_s) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), envp.data()), 0);
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

// Waits until diagnostics.csv in `dir` has `rows` data rows (false after
// 120 s or when the child exits first).
bool wait_rows(pid_t pid, const std::string& dir, std::size_t rows) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120)) {
    if (fs::exists(dir + "/diagnostics.csv") && csv(dir + "/diagnostics.csv").size() > rows) return true;
    if (kill(pid, 0) != 0) return false;
    int st = 0;
    if (waitpid(pid, &st, WNOHANG) == pid) {
      ADD_FAILURE() << "the run ended before the signal: " << slurp(dir + ".log");
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

int wait_exit(pid_t pid) {
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : (WIFSIGNALED(st) ? 1000 + WTERMSIG(st) : -1);
}

// Signals a run of the friction contact scene after `rows` steps.
long interrupt_and_restart(int sig, int expected_exit) {
  const Case c{"sig" + std::to_string(sig), disk_wall, friction_sets, 1e-3, 0};
  const std::string dir = fresh(c.tag);
  const pid_t pid = spawn({exe, "run", disk_wall, "--set", "Contact/friction=0.3", "--set",
                           "MPM Bodies/disk/initial velocity={100.0, 30.0}", "--set", "Output/frame every=3",
                           "--set", "Time/end time=1.0", "-o", dir},
                          dir + ".log");
  EXPECT_TRUE(wait_rows(pid, dir, 4));
  kill(pid, sig);
  EXPECT_EQ(wait_exit(pid), expected_exit) << slurp(dir + ".log");
  const std::string log = slurp(dir + ".log");
  EXPECT_NE(log.find("continue with: bfemp restart " + dir), std::string::npos) << log;
  const bfemp::Checkpoint ck = bfemp::read_checkpoint(dir + "/checkpoint.h5");
  EXPECT_GE(ck.step, 4);
  // The last frame is the interrupted step's state.
  const int last = ck.frames - 1;
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%06d", last);
  EXPECT_EQ(bfemp::read_attribute(dir + "/bfemp.h5", name, "step"), ck.step);
  const std::string ref = fresh(c.tag + "_ref");
  const std::string end = end_time(c, ck.step + 4);
  EXPECT_EQ(run_bfemp("run " + disk_wall + " " + friction_sets + " " + end + " -o " + ref, ref + ".log"), 0)
      << slurp(ref + ".log");
  EXPECT_EQ(run_bfemp("restart " + dir + " " + end, dir + ".restart.log"), 0) << slurp(dir + ".restart.log");
  expect_same_checkpoint(ref, dir);
  return ck.step;
}

}  // namespace

TEST(Restart, FemSceneContinuesBitForBit) {
  restart_equals_uninterrupted({"fem", squash, "--set 'Output/frame every=3'", 1e-2, 5});
  // Newmark carries the acceleration a^n across the restart.
  restart_equals_uninterrupted(
      {"fem_nm", squash, "--set 'Output/frame every=3' --set 'Time/integrator=newmark'", 1e-2, 5});
}

TEST(Restart, MpmSceneWithExtendContinuesBitForBit) {
  const Case c{"mpm_extend", thrown_scene(), "", 1e-2, 6};
  const bfemp::Checkpoint mid = restart_equals_uninterrupted(c);
  // The grid grew before the restart and again after it.
  const auto end = bfemp::read_checkpoint(dir_of("mpm_extend_other") + "/checkpoint.h5");
  EXPECT_GE(mid.ints("grid_extensions")[0], 1);
  EXPECT_GT(end.ints("grid_extensions")[0], mid.ints("grid_extensions")[0])
      << "the grid should extend after the restart too";
}

TEST(Restart, FrictionContactBackwardEulerBitForBit) {
  restart_equals_uninterrupted({"contact_be", disk_wall, friction_sets, 1e-3, 6});
  const auto rows = csv(dir_of("contact_be_full") + "/diagnostics.csv");
  int friction_iters_max = 0;
  long pairs = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    friction_iters_max = std::max(friction_iters_max, std::stoi(rows[i][20]));
    pairs = std::max(pairs, std::stol(rows[i][17]));
  }
  EXPECT_GT(pairs, 0) << "the scene must be in contact";
  EXPECT_GE(friction_iters_max, 2) << "the friction loop must be active";
}

TEST(Restart, FrictionContactNewmarkBitForBit) {
  restart_equals_uninterrupted(
      {"contact_nm", disk_wall, friction_sets + " --set 'Time/integrator=newmark' --set 'MPM/when particles leave=extend'",
       1e-3, 6});
}

// 'MPM/sort particles every': the particles are reordered by cell at steps
// 1, 4, 7, ...; the restart at step 6 sorts at step 7 as the uninterrupted run
// does, into the same order (within a cell by id), so the continuation is
// bit for bit; checkpoints and frames are in id order.
TEST(Restart, SortedParticlesContinueBitForBit) {
  restart_equals_uninterrupted({"contact_sorted", disk_wall, friction_sets + " --set 'MPM/sort particles every=3'", 1e-3, 6});
  const std::string log = slurp(dir_of("contact_sorted_full") + ".log");
  EXPECT_NE(log.find("particle sorts      4 (by grid cell, every 3 steps)"), std::string::npos) << log;
  // A checkpoint between sorts (steps 1 and 5 sort, the restart is at 6):
  // the checkpoint carries the order of step 5's sort, and the restarted
  // run continues in it until step 9 sorts again.
  const bfemp::Checkpoint mid =
      restart_equals_uninterrupted({"contact_sorted4", disk_wall, friction_sets + " --set 'MPM/sort particles every=4'", 1e-3, 6});
  ASSERT_TRUE(mid.has("particle_order"));
  const auto& order = mid.ints("particle_order");
  long moved = 0;
  for (std::size_t k = 0; k < order.size(); ++k) moved += order[k] != static_cast<long long>(k);
  EXPECT_GT(moved, 0) << "the sort must have reordered the particles";
}

// Sorted and unsorted particle order give the same run to round-off: the
// friction contact scene with a sort before every step against none. Only
// summation orders differ (P2G sums, cell sums of the assembly), so the two
// runs' Newton iterates differ by round-off amplified by the solves; every
// particle field, by id, agrees to 1e-9 of its largest magnitude (a particle
// written at another's row would differ by O(1)), and the step-by-step
// Newton counts and contact-pair counts are equal. The frames (written in id
// order from the sorted run's permuted particles and contact forces) agree
// in the same way. Both runs solve every Newton direction to the reuse
// tolerance ('forcing term: fixed'): with the adaptive forcing term a CG on
// the previous factor that stops at a loose tolerance may stop one iteration
// earlier in one order than in the other, and a step's Newton count then
// differs by one (43 against 44 at step 2) while every field still agrees
// to 1e-9; the counts compared here are the sort's, not the forcing term's.
TEST(ParticleSort, SortedAndUnsortedRunsAgreeToRoundOff) {
  const std::string exact = friction_sets + " --set 'Linear Solver/Cholmod/forcing term=fixed'";
  const Case c{"sort", disk_wall, exact, 1e-3, 12};
  const std::string plain = fresh("sort_off"), sorted = fresh("sort_on");
  ASSERT_EQ(run_bfemp("run " + disk_wall + " " + exact + " " + end_time(c, c.n) + " -o " + plain, plain + ".log"), 0)
      << slurp(plain + ".log");
  ASSERT_EQ(run_bfemp("run " + disk_wall + " " + exact + " --set 'MPM/sort particles every=1' " +
                          end_time(c, c.n) + " -o " + sorted,
                      sorted + ".log"),
            0)
      << slurp(sorted + ".log");
  EXPECT_NE(slurp(sorted + ".log").find("particle sorts      12 (by grid cell, every 1 steps)"), std::string::npos);
  const bfemp::Checkpoint a = bfemp::read_checkpoint(plain + "/checkpoint.h5");
  const bfemp::Checkpoint b = bfemp::read_checkpoint(sorted + "/checkpoint.h5");
  auto close = [](const std::vector<double>& x, const std::vector<double>& y, const std::string& what) {
    ASSERT_EQ(x.size(), y.size()) << what;
    ASSERT_FALSE(x.empty()) << what;
    double scale = 0, worst = 0;
    for (double v : x) scale = std::max(scale, std::abs(v));
    for (std::size_t i = 0; i < x.size(); ++i) worst = std::max(worst, std::abs(x[i] - y[i]));
    EXPECT_LE(worst, 1e-9 * scale) << what << ": worst difference " << worst << ", largest value " << scale;
  };
  for (const char* name : {"particle_x", "particle_v", "particle_F", "particle_C", "particle_mass", "particle_volume0", "fem_x", "fem_v"})
    close(a.arrays.at(name).real, b.arrays.at(name).real, name);
  EXPECT_EQ(a.ints("particle_body"), b.ints("particle_body"));
  // The last frame, read from bfemp.h5 as ParaView does.
  char frame[64];
  std::snprintf(frame, sizeof frame, "/frame_%06d", a.frames - 1);
  for (const char* name : {"particle_positions", "particle_velocities", "particle_J", "particle_contact_force"})
    close(bfemp::read_dataset(plain + "/bfemp.h5", std::string(frame) + "/" + name, nullptr),
          bfemp::read_dataset(sorted + "/bfemp.h5", std::string(frame) + "/" + name, nullptr), name);
  EXPECT_EQ(bfemp::read_dataset_int(plain + "/bfemp.h5", std::string(frame) + "/particle_body", nullptr),
            bfemp::read_dataset_int(sorted + "/bfemp.h5", std::string(frame) + "/particle_body", nullptr));
  const auto ra = csv(plain + "/diagnostics.csv"), rb = csv(sorted + "/diagnostics.csv");
  ASSERT_EQ(ra.size(), rb.size());
  long pairs = 0;
  for (std::size_t i = 1; i < ra.size(); ++i) {
    EXPECT_EQ(ra[i][10], rb[i][10]) << "Newton iterations, step " << ra[i][0];
    EXPECT_EQ(ra[i][17], rb[i][17]) << "contact pairs, step " << ra[i][0];
    pairs = std::max(pairs, std::stol(ra[i][17]));
  }
  EXPECT_GT(pairs, 0) << "the scene must be in contact";
}

TEST(Restart, SigtermWritesACheckpointAndExits143) { interrupt_and_restart(SIGTERM, 143); }

TEST(Restart, SigintWritesACheckpointAndExits130) { interrupt_and_restart(SIGINT, 130); }

TEST(Restart, SigkillLeavesReadableFramesAndRestartsFromTheLastCheckpoint) {
  const std::string dir = fresh("sigkill");
  const pid_t pid = spawn({exe, "run", disk_wall, "--set", "Contact/friction=0.3", "--set",
                           "MPM Bodies/disk/initial velocity={100.0, 30.0}", "--set", "Output/frame every=1",
                           "--set", "Output/checkpoint every=4", "--set", "Time/end time=1.0", "-o", dir},
                          dir + ".log");
  ASSERT_TRUE(wait_rows(pid, dir, 10));
  kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid), 1000 + SIGKILL);
  // Every dataset the XDMF references exists with the stated dimensions.
  const std::string xdmf = slurp(dir + "/bfemp.xdmf");
  const std::regex item(R"re(<DataItem[^>]*Dimensions="([0-9 ]+)"[^>]*>\s*bfemp\.h5:([^<\s]+)\s*</DataItem>)re");
  int items = 0;
  for (auto it = std::sregex_iterator(xdmf.begin(), xdmf.end(), item); it != std::sregex_iterator(); ++it) {
    std::istringstream dims((*it)[1].str());
    std::size_t n = 1;
    for (std::size_t d; dims >> d;) n *= d;
    const auto v = bfemp::read_dataset(dir + "/bfemp.h5", (*it)[2].str(), nullptr);
    EXPECT_EQ(v.size(), n) << (*it)[2].str();
    ++items;
  }
  EXPECT_GT(items, 20) << xdmf;
  const bfemp::Checkpoint ck = bfemp::read_checkpoint(dir + "/checkpoint.h5");
  EXPECT_EQ(ck.step % 4, 0);
  EXPECT_GE(ck.step, 4);
  const Case c{"sigkill", disk_wall, friction_sets + " --set 'Output/frame every=1'", 1e-3, 0};
  const std::string ref = fresh("sigkill_ref");
  const std::string end = end_time(c, ck.step + 3);
  ASSERT_EQ(run_bfemp("run " + disk_wall + " " + c.sets + " " + end + " -o " + ref, ref + ".log"), 0)
      << slurp(ref + ".log");
  ASSERT_EQ(run_bfemp("restart " + dir + " " + end, dir + ".restart.log"), 0) << slurp(dir + ".restart.log");
  expect_same_checkpoint(ref, dir);
  expect_same_diagnostics(ref, dir);  // rows after the checkpoint were dropped, then rewritten
  // frames: one per step, 0 .. step, no duplicate left from before the kill
  EXPECT_EQ(bfemp::read_checkpoint(dir + "/checkpoint.h5").frames, ck.step + 3 + 1);
}

// The explicit stepper on the B1 blocks (in contact from step 1), XPIC(5) so
// that the v* task and the stored pass-1 Delta v cross the restart; a fixed dt
// below the CFL limit (1.29e-6 s) so that the step count sets the end time.
const std::string b1 = src + "/inputs/b1_compress.yaml";
const std::string explicit_sets =
    "--set 'Time/dt=1e-6' --set 'Explicit/update=XPIC' --set 'Output/frame every=7' --set 'Output/progress every=0'";

TEST(Restart, ExplicitSceneContinuesBitForBit) {
  restart_equals_uninterrupted({"explicit", b1, explicit_sets, 1e-6, 25});
  const auto rows = csv(dir_of("explicit_full") + "/diagnostics.csv");
  ASSERT_EQ(rows[0][4], "contact_nodes");
  for (std::size_t i = 1; i < rows.size(); ++i) EXPECT_GT(std::stol(rows[i][4]), 0) << "step " << rows[i][0];
  // Every frame is in the XDMF index: 0, 7, 14, 21, 28, 35, 42, 49, 50 (the
  // restarted directory also keeps step 25, the last frame of its first run).
  const std::string xdmf = slurp(dir_of("explicit_full") + "/bfemp.xdmf");
  std::size_t times = 0;
  for (std::size_t at = xdmf.find("<Time "); at != std::string::npos; at = xdmf.find("<Time ", at + 1)) ++times;
  EXPECT_EQ(times, 9u) << xdmf;
  EXPECT_NE(xdmf.find("particle_material_class"), std::string::npos);
}

TEST(Restart, ExplicitSigtermWritesACheckpointAndExits143) {
  const std::string dir = fresh("explicit_sigterm");
  const pid_t pid = spawn({exe, "run", b1, "--set", "Time/dt=1e-6", "--set", "Explicit/update=XPIC", "--set",
                           "Output/frame every=7", "--set", "Output/progress every=0", "--set", "Time/end time=1.0",
                           "-o", dir},
                          dir + ".log");
  ASSERT_TRUE(wait_rows(pid, dir, 12));
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(pid), 143) << slurp(dir + ".log");
  EXPECT_NE(slurp(dir + ".log").find("continue with: bfemp restart " + dir), std::string::npos) << slurp(dir + ".log");
  const bfemp::Checkpoint ck = bfemp::read_checkpoint(dir + "/checkpoint.h5");
  EXPECT_GE(ck.step, 12);
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%06d", ck.frames - 1);
  EXPECT_EQ(bfemp::read_attribute(dir + "/bfemp.h5", name, "step"), ck.step);
  const Case c{"explicit_sigterm", b1, explicit_sets, 1e-6, 0};
  const std::string ref = fresh("explicit_sigterm_ref");
  const std::string end = end_time(c, ck.step + 5);
  ASSERT_EQ(run_bfemp("run " + b1 + " " + explicit_sets + " " + end + " -o " + ref, ref + ".log"), 0)
      << slurp(ref + ".log");
  ASSERT_EQ(run_bfemp("restart " + dir + " " + end, dir + ".restart.log"), 0) << slurp(dir + ".restart.log");
  expect_same_checkpoint(ref, dir);
  expect_same_diagnostics(ref, dir);
}

TEST(Restart, SetOfAShapeChangingKeyIsRefused) {
  const Case c{"refuse", squash, "", 1e-2, 2};
  const std::string dir = fresh("refuse");
  ASSERT_EQ(run_bfemp("run " + squash + " " + end_time(c, 2) + " -o " + dir, dir + ".log"), 0);
  EXPECT_EQ(run_bfemp("restart " + dir + " --set 'Materials/soft/E=2e5'", dir + ".r.log"), 2);
  EXPECT_NE(slurp(dir + ".r.log").find("'Materials/soft/E'"), std::string::npos) << slurp(dir + ".r.log");
  EXPECT_EQ(run_bfemp("restart " + root + "/no_such_run", dir + ".r2.log"), 2);
  EXPECT_NE(slurp(dir + ".r2.log").find("checkpoint.h5"), std::string::npos) << slurp(dir + ".r2.log");
  EXPECT_EQ(run_bfemp("restart " + dir + " " + end_time(c, 4) + " --set 'Linear Solver/type=KLU2'", dir + ".r3.log"), 0)
      << slurp(dir + ".r3.log");
}

TEST(Restart, ANewRunIntoTheDirectoryDropsTheOldCheckpoint) {
  // Run A completes (checkpoint at step 2); run B into the same directory
  // fails at step 1: the checkpoint there must then be B's (its state after
  // 0 steps, its overrides), never A's, so a restart continues B over B's files.
  const Case c{"stale", squash, "", 1e-2, 2};
  const std::string dir = fresh("stale");
  ASSERT_EQ(run_bfemp("run " + squash + " " + end_time(c, 2) + " -o " + dir, dir + ".a.log"), 0);
  ASSERT_TRUE(fs::exists(dir + "/checkpoint.h5"));
  EXPECT_EQ(bfemp::read_checkpoint(dir + "/checkpoint.h5").step, 2);
  EXPECT_EQ(run_bfemp("run " + squash + " --set 'Newton/max iterations=1' -o " + dir, dir + ".b.log"), 3)
      << slurp(dir + ".b.log");
  const bfemp::Checkpoint ck = bfemp::read_checkpoint(dir + "/checkpoint.h5");
  EXPECT_EQ(ck.step, 0);
  EXPECT_NE(ck.text("overrides").find("Newton/max iterations=1"), std::string::npos) << ck.text("overrides");
  EXPECT_EQ(run_bfemp("restart " + dir + " --set 'Newton/max iterations=300' " + end_time(c, 2), dir + ".r.log"), 0)
      << slurp(dir + ".r.log");
  EXPECT_EQ(bfemp::read_checkpoint(dir + "/checkpoint.h5").step, 2);
}

TEST(Restart, AChangedMeshFileIsRefused) {
  const std::string dir = fresh("mesh_file"), work = root + "/mesh_file_scene";
  fs::remove_all(work);
  fs::create_directories(work);
  fs::copy_file(src + "/tests/data/square_tri.msh", work + "/square.msh");
  std::ofstream(work + "/scene.yaml") << R"(bfemp:
  dimension: 2
  gravity: [0.0, -9.81]
  Time:
    dt: 1.0e-2
    end time: 2.5e-2
  Output:
    progress every: 0
  Materials:
    soft:
      E: 1.0e5
      nu: 0.3
      density: 1000.0
  FEM Bodies:
    block:
      material: soft
      Mesh:
        file: square.msh
)";
  ASSERT_EQ(run_bfemp("run " + work + "/scene.yaml -o " + dir, dir + ".log"), 0) << slurp(dir + ".log");
  // Unchanged: the restart goes on.
  EXPECT_EQ(run_bfemp("restart " + dir + " --set 'Time/end time=0.035'", dir + ".r1.log"), 0) << slurp(dir + ".r1.log");
  std::string msh = slurp(work + "/square.msh");
  const auto at = msh.find("\n1 1 0\n");  // the corner node (1, 1)
  ASSERT_NE(at, std::string::npos);
  msh.replace(at, 7, "\n1 1.01 0\n");
  std::ofstream(work + "/square.msh") << msh;
  EXPECT_EQ(run_bfemp("restart " + dir + " --set 'Time/end time=0.045'", dir + ".r2.log"), 2) << slurp(dir + ".r2.log");
  EXPECT_NE(slurp(dir + ".r2.log").find("FEM mesh differs"), std::string::npos) << slurp(dir + ".r2.log");
}

// A solver failure (here Newton over a cap of 15 iterations at the disk's
// impact on the wall) exits 3 naming the step, after checkpointing the state
// of the last completed step; restarting from it with a higher cap gives the
// run that had that cap from the start, bit for bit.
TEST(Restart, ASolverFailureCheckpointsTheLastCompletedStep) {
  const Case c{"failure", disk_wall, friction_sets, 1e-3, 6};
  const std::string full = fresh("failure_full"), failed = fresh("failure_failed");
  const std::string high = " --set 'Newton/max iterations=300'";
  EXPECT_EQ(run_bfemp("run " + c.scene + " " + c.sets + high + " " + end_time(c, 2 * c.n) + " -o " + full,
                      full + ".log"),
            0)
      << slurp(full + ".log");
  EXPECT_EQ(run_bfemp("run " + c.scene + " " + c.sets + " --set 'Newton/max iterations=15' " + end_time(c, 2 * c.n) +
                          " -o " + failed,
                      failed + ".log"),
            3)
      << slurp(failed + ".log");
  const std::string log = slurp(failed + ".log");
  EXPECT_NE(log.find("solver failure at step"), std::string::npos) << log;
  EXPECT_NE(log.find("is checkpointed"), std::string::npos) << log;
  EXPECT_NE(log.find("bfemp restart " + failed), std::string::npos) << log;
  const bfemp::Checkpoint ck = bfemp::read_checkpoint(failed + "/checkpoint.h5");
  EXPECT_GE(ck.step, 1) << "the cap should let the first step through";
  EXPECT_LT(ck.step, 2 * c.n);
  EXPECT_NE(log.find("step " + std::to_string(ck.step + 1) + " "), std::string::npos) << log;
  EXPECT_EQ(run_bfemp("restart " + failed + high + " " + end_time(c, 2 * c.n), failed + ".restart.log"), 0)
      << slurp(failed + ".restart.log");
  expect_same_checkpoint(full, failed);
  expect_same_diagnostics(full, failed);
}
