// The mutation test's runner (mutation_test.cpp): runs
// `pdyn run mutant.yaml --steps 3 --quiet` in each folder listed in a file,
// each in a child process forked from this one, and writes each child's wait
// status, or -1 if it was killed after the timeout, one per line.
//
// Why fork instead of starting `pdyn`: a fresh `pdyn` process spends most of
// a 3-step run (about 50 ms of its CPU on the 2-core machine) in the dynamic
// loader, linking the program and opening every plugin library. This process
// opens them all once; a child forked from it finds them open and runs what
// the program's main() runs, cli::run_command, with its standard output and
// error on /dev/null, as the test ran the program. The test also runs a
// sample of the mutants with the real program and compares the statuses.
//
// This process never runs a command itself, so no OpenMP team exists when it
// forks (a team's threads would not exist in the child).
//
//   pdyn_mutation_runner LIST RESULTS TIMEOUT_SECONDS
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "pdyn/host/registry.hpp"

namespace {

// In the child: the command, as `pdyn` would run it in `folder`. Never
// returns; an escaping exception ends the child as it would end the program
// (std::terminate, a signal the test reports).
[[noreturn]] void run_in_child(const std::string& folder, const sigset_t& mask) {
  sigprocmask(SIG_SETMASK, &mask, nullptr);
  const int null = open("/dev/null", O_WRONLY);
  if (null < 0 || dup2(null, STDOUT_FILENO) < 0 || dup2(null, STDERR_FILENO) < 0 ||
      chdir(folder.c_str()) != 0) {
    _exit(125);
  }
  const int status = pdyn::cli::run_command({"run", "mutant.yaml", "--steps", "3", "--quiet"},
                                            std::cout, std::cerr, false);
  std::cout.flush();
  std::cerr.flush();
  _exit(status);  // not exit(): the parent's atexit handlers are not the child's to run
}

// The child's wait status, or -1 after killing it at `timeout_s`. SIGCHLD is
// blocked in this process, so sigtimedwait() sleeps until a child ends.
int wait_for(pid_t pid, double timeout_s) {
  sigset_t chld;
  sigemptyset(&chld);
  sigaddset(&chld, SIGCHLD);
  timespec start{};
  clock_gettime(CLOCK_MONOTONIC, &start);
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    const double left = timeout_s - (static_cast<double>(now.tv_sec - start.tv_sec) +
                                     1e-9 * static_cast<double>(now.tv_nsec - start.tv_nsec));
    if (left <= 0) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    const auto whole = static_cast<time_t>(left);
    const timespec wait{whole, static_cast<long>((left - static_cast<double>(whole)) * 1e9)};
    sigtimedwait(&chld, nullptr, &wait);  // a SIGCHLD, the timeout or EINTR: look again
  }
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: pdyn_mutation_runner LIST RESULTS TIMEOUT_SECONDS\n";
    return 2;
  }
  const double timeout_s = std::atof(argv[3]);
  // Every library pdyn's search path holds, open for the children to share.
  pdyn::PluginRegistry preloaded;
  preloaded.discover(
      pdyn::PluginRegistry::search_path({}, pdyn::DefaultFolders::LibraryAndProgram));

  sigset_t chld, old;
  sigemptyset(&chld);
  sigaddset(&chld, SIGCHLD);
  sigprocmask(SIG_BLOCK, &chld, &old);
  std::ifstream list(argv[1]);
  std::ofstream results(argv[2]);
  for (std::string folder; std::getline(list, folder);) {
    std::cout.flush();
    std::cerr.flush();
    const pid_t pid = fork();
    if (pid < 0) {
      std::cerr << "pdyn_mutation_runner: fork failed: " << std::strerror(errno) << "\n";
      return 1;
    }
    if (pid == 0) run_in_child(folder, old);
    results << wait_for(pid, timeout_s) << "\n" << std::flush;
  }
  return results ? 0 : 1;
}
