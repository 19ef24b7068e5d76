// Crash isolation for the conformance kit (see isolation.hpp): the child's
// messages, the parent's supervision and the wire format between them.
#include "isolation.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

#include "pdyn/host/crash_report.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"

namespace pdyn::conformance::detail {

namespace {

thread_local Worker* t_worker = nullptr;
// Whether the process forked from had a single thread (threads_usable()).
bool g_parent_single_threaded = true;

// The threads of this process, from /proc/self/task (Linux): a pool that
// libgomp started stays there, idle, for the life of the process.
int thread_count() {
  int n = 0;
  std::error_code ec;
  for (auto it = std::filesystem::directory_iterator("/proc/self/task", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
    ++n;
  }
  return n;
}

// ---- wire format ----
//
// A message is its length (u32, native order: both ends are this program),
// a type byte and a payload:
//   'B' u64 position, string name        a check starts
//   'R' u64 position, result             a result of the report
//   'E'                                  the sequence is done
// A string is a u32 length and its bytes; a result is its name, verdict
// (u8), measured and bound (the doubles' bits) and detail.

class Writer {
 public:
  explicit Writer(char type) : buf_(4, '\0') { buf_ += type; }
  Writer& u64(std::uint64_t v) { return raw(&v, sizeof v); }
  Writer& f64(double v) { return raw(&v, sizeof v); }
  Writer& str(const std::string& s) {
    const auto n = static_cast<std::uint32_t>(s.size());
    raw(&n, sizeof n);
    buf_ += s;
    return *this;
  }
  Writer& result(const CheckResult& r) {
    str(r.name);
    buf_ += static_cast<char>(r.verdict);
    return f64(r.measured).f64(r.bound).str(r.detail);
  }
  // Writes the whole message; a parent that is gone ends the child (SIGPIPE).
  void send(int fd) {
    const auto n = static_cast<std::uint32_t>(buf_.size() - 4);
    std::memcpy(buf_.data(), &n, sizeof n);
    for (std::size_t done = 0; done < buf_.size();) {
      const ssize_t w = ::write(fd, buf_.data() + done, buf_.size() - done);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) ::_exit(120);
      done += static_cast<std::size_t>(w);
    }
  }

 private:
  Writer& raw(const void* p, std::size_t n) {
    buf_.append(static_cast<const char*>(p), n);
    return *this;
  }
  std::string buf_;
};

class Reader {
 public:
  explicit Reader(std::string_view s) : s_(s) {}
  std::uint64_t u64() { return raw<std::uint64_t>(); }
  double f64() { return raw<double>(); }
  std::string str() {
    const auto n = raw<std::uint32_t>();
    std::string out(s_.substr(at_, n));
    at_ += n;
    return out;
  }
  CheckResult result() {
    CheckResult r;
    r.name = str();
    r.verdict = static_cast<Verdict>(raw<char>());
    r.measured = f64();
    r.bound = f64();
    r.detail = str();
    return r;
  }

 private:
  template <class T>
  T raw() {
    T v{};
    std::memcpy(&v, s_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::string_view s_;
  std::size_t at_ = 0;
};

// ---- the child ----

// The child must die of the plugin's signal, so that the parent can name it:
// a sanitizer's or the host's handler would turn it into an exit status.
void reset_fatal_signals() {
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS}) {
    std::signal(sig, SIG_DFL);
  }
}

[[noreturn]] void run_child(int fd, const std::function<void(std::vector<CheckResult>&)>& sequence,
                            const std::map<std::size_t, CheckResult>& replaced) {
  reset_fatal_signals();
  // GNU libgomp cannot start a parallel team in a forked child of a process
  // whose main thread already had one (its threads are not copied; the
  // child hangs). One thread avoids the team, and changes no result: pdyn's
  // results are bit-identical for every thread count.
  set_threads(1);
  Worker worker(fd, replaced);
  t_worker = &worker;
  std::vector<CheckResult> out;
  try {
    sequence(out);
  } catch (...) {
    // run_checks catches what the checks throw; nothing else may escape here.
  }
  worker.finish(out);
  ::close(fd);
  // No atexit handlers, no flushing of the parent's buffers, no leak report.
  ::_exit(0);
}

std::string describe_status(int status, bool timed_out, double timeout) {
  if (timed_out) return fmt::format("timed out after {:g} s", timeout);
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = crash::signal_name(sig);
    return name ? fmt::format("crashed with {}", name) : fmt::format("crashed with signal {}", sig);
  }
  if (WIFEXITED(status)) return fmt::format("exited with status {}", WEXITSTATUS(status));
  return "stopped";
}

// One child's run: the results it sent, the check it was in when it ended,
// and how it ended.
struct ChildRun {
  bool finished = false;   // sent the end mark
  bool timed_out = false;  // killed after `timeout` s without a message
  int status = 0;          // waitpid status
  std::optional<std::pair<std::size_t, std::string>> current;  // check in progress
};

ChildRun supervise(pid_t pid, int fd, double timeout, std::vector<CheckResult>& report) {
  using Clock = std::chrono::steady_clock;
  ChildRun run;
  std::string buf;
  auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  char chunk[4096];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() < 0) {
      run.timed_out = true;
      ::kill(pid, SIGKILL);
      break;
    }
    pollfd p{fd, POLLIN, 0};
    const int ready =
        ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count() + 1, 1 << 30)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) continue;  // the deadline check above decides
    const ssize_t got = ::read(fd, chunk, sizeof chunk);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;  // the child ended (or closed its end)
    buf.append(chunk, static_cast<std::size_t>(got));
    // Every complete message; each one restarts the clock.
    std::size_t at = 0;
    while (buf.size() - at >= 4) {
      std::uint32_t n = 0;
      std::memcpy(&n, buf.data() + at, sizeof n);
      if (buf.size() - at - 4 < n) break;
      const std::string_view msg(buf.data() + at + 4, n);
      at += 4 + n;
      deadline = Clock::now() + std::chrono::duration<double>(timeout);
      Reader r(msg.substr(1));
      switch (msg[0]) {
        case 'B': {
          const auto pos = static_cast<std::size_t>(r.u64());
          run.current.emplace(pos, r.str());
          break;
        }
        case 'R': {
          const auto pos = static_cast<std::size_t>(r.u64());
          CheckResult result = r.result();
          // A replaying child resends what an earlier one did: keep the first.
          if (pos == report.size()) report.push_back(std::move(result));
          if (run.current && run.current->first == pos) run.current.reset();
          break;
        }
        case 'E':
          run.finished = true;
          break;
      }
    }
    buf.erase(0, at);
  }
  while (::waitpid(pid, &run.status, 0) < 0 && errno == EINTR) {
  }
  return run;
}

}  // namespace

const CheckResult* Worker::begin(const std::vector<CheckResult>& out, const std::string& name) {
  flush(out);
  const auto it = replaced_.find(out.size());
  if (it != replaced_.end()) return &it->second;
  Writer('B').u64(out.size()).str(name).send(fd_);
  return nullptr;
}

void Worker::flush(const std::vector<CheckResult>& out) {
  for (; sent_ < out.size(); ++sent_) Writer('R').u64(sent_).result(out[sent_]).send(fd_);
}

void Worker::finish(const std::vector<CheckResult>& out) {
  flush(out);
  Writer('E').send(fd_);
}

Worker* current_worker() noexcept { return t_worker; }

bool threads_usable() noexcept { return t_worker == nullptr || g_parent_single_threaded; }

std::vector<CheckResult> run_isolated(
    const std::function<void(std::vector<CheckResult>&)>& sequence, double timeout) {
  std::vector<CheckResult> report;
  // Checks that ended a child, by their place in the report, with the
  // result a later child reports for them instead of running them again.
  std::map<std::size_t, CheckResult> replaced;
  // Each child that does not finish adds an entry to `replaced`, so there
  // are at most as many children as checks; the bound is a safeguard.
  for (int child = 0; child < 256; ++child) {
    int fds[2];
    if (::pipe(fds) != 0) {
      report.push_back({"run", Verdict::Fail, 0, 0,
                        fmt::format("cannot create a pipe: {}", std::strerror(errno))});
      return report;
    }
    std::fflush(nullptr);  // or the child's exit could print the parent's buffered output twice
    g_parent_single_threaded = thread_count() <= 1;
    const pid_t pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
      report.push_back({"run", Verdict::Fail, 0, 0,
                        fmt::format("cannot start a child process: {}", std::strerror(errno))});
      return report;
    }
    if (pid == 0) {
      ::close(fds[0]);
      run_child(fds[1], sequence, replaced);
    }
    ::close(fds[1]);
    const ChildRun run = supervise(pid, fds[0], timeout, report);
    ::close(fds[0]);
    if (run.finished && !run.timed_out) return report;
    const std::string what = describe_status(run.status, run.timed_out, timeout);
    if (!run.current) {
      // Between checks: only kit code and a plugin's destructor run there.
      report.push_back({"run", Verdict::Fail, 0, 0,
                        fmt::format("the check process {} outside any check", what)});
      return report;
    }
    const std::size_t pos = run.current->first;
    if (replaced.count(pos) != 0 || pos > report.size()) break;  // cannot happen: no progress
    if (pos == report.size()) {
      report.push_back({run.current->second, Verdict::Fail, 0, 0, what});
    }
    // (A check that passed in an earlier child and ended this one keeps its
    // first result; it is not run again either.)
    replaced.emplace(pos, report[pos]);
  }
  report.push_back({"run", Verdict::Fail, 0, 0, "the check processes made no progress"});
  return report;
}

}  // namespace pdyn::conformance::detail
