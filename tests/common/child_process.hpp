#pragma once
// Runs real child processes for tests: a small pool that starts commands
// (argv, extra environment, stdout+stderr into one file), at most `parallel`
// at once, each killed with SIGKILL after `timeout_s`, and reports each one's
// exit status, the signal that ended it, whether it timed out, its output and
// wall time. POSIX only (fork/exec/waitpid).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace bfemp::testing {

struct ChildJob {
  std::vector<std::string> argv;
  std::vector<std::string> env;  // "NAME=value", set on top of the parent's environment
  std::string output_file;       // stdout and stderr
};

struct ChildResult {
  int exit_code = -1;   // WEXITSTATUS when it exited
  int signal = 0;       // the signal that ended it (SIGKILL after a timeout)
  bool timed_out = false;
  double wall_s = 0;
  std::string output;
};

// Runs every job; results in the order of `jobs`.
inline std::vector<ChildResult> run_children(const std::vector<ChildJob>& jobs, int parallel, double timeout_s) {
  using clock = std::chrono::steady_clock;
  struct Running {
    pid_t pid;
    std::size_t job;
    clock::time_point start;
    bool killed;
  };
  std::vector<ChildResult> results(jobs.size());
  std::vector<Running> running;
  std::size_t next = 0;
  auto start_one = [&](std::size_t j) {
    const ChildJob& job = jobs[j];
    const pid_t pid = fork();
    if (pid == 0) {
      const int fd = open(job.output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
      }
      for (const auto& e : job.env) putenv(const_cast<char*>(e.c_str()));
      std::vector<char*> args;
      for (const auto& a : job.argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    running.push_back({pid, j, clock::now(), false});
  };
  while (next < jobs.size() || !running.empty()) {
    while (next < jobs.size() && static_cast<int>(running.size()) < parallel) start_one(next++);
    bool reaped = false;
    for (std::size_t k = 0; k < running.size();) {
      Running& r = running[k];
      int status = 0;
      const pid_t w = waitpid(r.pid, &status, WNOHANG);
      const double el = std::chrono::duration<double>(clock::now() - r.start).count();
      if (w == r.pid) {
        ChildResult& res = results[r.job];
        res.wall_s = el;
        res.timed_out = r.killed;
        if (WIFEXITED(status)) res.exit_code = WEXITSTATUS(status);
        if (WIFSIGNALED(status)) res.signal = WTERMSIG(status);
        std::ifstream in(jobs[r.job].output_file);
        std::stringstream ss;
        ss << in.rdbuf();
        res.output = ss.str();
        running.erase(running.begin() + static_cast<long>(k));
        reaped = true;
        continue;
      }
      if (!r.killed && el > timeout_s) {
        kill(r.pid, SIGKILL);  // our own child, by its id
        r.killed = true;
      }
      ++k;
    }
    if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return results;
}

}  // namespace bfemp::testing
