// The current-plugin-call record and `pdyn run`'s fatal-signal handler
// (see crash_report.hpp).
#include "pdyn/host/crash_report.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

#include "pdyn/host/scene.hpp"

namespace pdyn::crash {

namespace fs = std::filesystem;

namespace {

constexpr int kFatalSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
constexpr std::size_t kSignalCount = std::size(kFatalSignals);

// Everything the handler prints or removes, formatted before the run.
struct Report {
  struct Entry {
    const std::string* label;  // the System's (or scene's) label string: its address is the key
    std::string text;          // "force 'nbody' (scene.yaml:12:5, library /p/lib.so)"
  };
  std::vector<Entry> entries;
  std::vector<std::string> temp_files;  // unlinked by the handler unless `keep`
  std::string removed_note;             // "; unfinished output removed: a.tmp-1, b.tmp-1"
  std::string kept_note;                // set before `keep` becomes true
  std::atomic<bool> keep{false};
  const PluginCall* const* installer_call = nullptr;  // the installing thread's record
  std::vector<char> alt_stack;  // a stack overflow in a plugin still gets its line
  stack_t old_stack{};
  struct sigaction old_actions[kSignalCount] {};
};

std::atomic<Report*> g_report{nullptr};
std::atomic<std::int64_t> g_step{0};

// The handler's line: static, because a crash may come from a stack overflow.
char g_line[16384];

struct Line {
  std::size_t n = 0;
  void add(const char* s, std::size_t len) noexcept {
    len = std::min(len, sizeof(g_line) - 1 - n);  // keep room for the newline
    std::memcpy(g_line + n, s, len);
    n += len;
  }
  void add(const char* s) noexcept { add(s, std::strlen(s)); }
  void add(const std::string& s) noexcept { add(s.data(), s.size()); }
  void add(std::int64_t v) noexcept {
    char digits[24];
    std::size_t k = 0;
    const bool negative = v < 0;
    std::uint64_t u = negative ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
    do {
      digits[k++] = static_cast<char>('0' + u % 10);
      u /= 10;
    } while (u > 0);
    if (negative) digits[k++] = '-';
    while (k > 0) add(&digits[--k], 1);
  }
};

extern "C" void on_fatal_signal(int sig) {
  // SA_RESETHAND has restored the default action already: a second fault in
  // here ends the process at once instead of looping.
  const int saved_errno = errno;
  const Report* r = g_report.load(std::memory_order_acquire);
  Line line;
  line.add("pdyn: ");
  const PluginCall* call = t_current_call;
  // A plugin's own worker thread (OpenMP) has no record: the call is the one
  // the stepping thread is making.
  if (!call && r && r->installer_call) call = *r->installer_call;
  if (call) {
    const Report::Entry* entry = nullptr;
    if (r) {
      for (const auto& e : r->entries) {
        if (e.label == call->label) entry = &e;
      }
    }
    if (entry) {
      line.add(entry->text);
    } else {
      line.add("plugin ");
      line.add(*call->label);
    }
    line.add(" crashed with ");
  } else {
    line.add("crashed with ");
  }
  const char* name = signal_name(sig);
  if (name) {
    line.add(name);
  } else {
    line.add("signal ");
    line.add(static_cast<std::int64_t>(sig));
  }
  if (call) {
    line.add(" in ");
    line.add(call->hook);
  } else {
    line.add(" outside any plugin call");
  }
  line.add(" at step ");
  line.add(g_step.load(std::memory_order_relaxed));
  if (r) {
    if (r->keep.load(std::memory_order_acquire)) {
      line.add(r->kept_note);
    } else if (!r->temp_files.empty()) {
      for (const auto& f : r->temp_files) ::unlink(f.c_str());
      line.add(r->removed_note);
    }
  }
  g_line[line.n++] = '\n';
  for (std::size_t done = 0; done < line.n;) {
    const ssize_t w = ::write(STDERR_FILENO, g_line + done, line.n - done);
    if (w <= 0) break;
    done += static_cast<std::size_t>(w);
  }
  errno = saved_errno;
  // Die of the same signal, so the exit status is 128 + signal and a core
  // dump (if enabled) shows the plugin's frame: the signal is blocked while
  // this handler runs, so it is delivered, with the default action, as soon
  // as the handler returns (a faulting instruction would also fault again).
  std::raise(sig);
}

// "force 'nbody' (scene.yaml:12:5, library /p/pdyn_force_nbody.so)", from a
// label "nbody (scene.yaml:12:5)".
std::string describe(const char* kind, const std::string& label, const Scene& scene) {
  std::string type = label, where;
  if (const auto open = label.find(" ("); open != std::string::npos && label.back() == ')') {
    type = label.substr(0, open);
    where = label.substr(open + 2, label.size() - open - 3);
  }
  std::string library;
  if (const auto it = scene.libraries.find(label); it != scene.libraries.end()) {
    library = it->second.string();
  }
  std::string inside = where;
  if (!library.empty()) inside += fmt::format("{}library {}", where.empty() ? "" : ", ", library);
  return inside.empty() ? fmt::format("{} '{}'", kind, type)
                        : fmt::format("{} '{}' ({})", kind, type, inside);
}

std::string file_list(const std::vector<std::string>& files) {
  std::string s;
  for (const auto& f : files) s += (s.empty() ? "" : ", ") + f;
  return s;
}

}  // namespace

const char* signal_name(int sig) noexcept {
  switch (sig) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGABRT:
      return "SIGABRT";
    case SIGTRAP:
      return "SIGTRAP";
    case SIGSYS:
      return "SIGSYS";
    case SIGKILL:
      return "SIGKILL";
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGHUP:
      return "SIGHUP";
    case SIGQUIT:
      return "SIGQUIT";
    case SIGPIPE:
      return "SIGPIPE";
    case SIGALRM:
      return "SIGALRM";
    case SIGXCPU:
      return "SIGXCPU";
    case SIGXFSZ:
      return "SIGXFSZ";
    case SIGUSR1:
      return "SIGUSR1";
    case SIGUSR2:
      return "SIGUSR2";
    default:
      return nullptr;
  }
}

void set_step(std::int64_t step) noexcept { g_step.store(step, std::memory_order_relaxed); }

namespace {
std::atomic<bool> g_reporting{false};
}  // namespace

ReportCrashes::ReportCrashes() noexcept { g_reporting = true; }
ReportCrashes::~ReportCrashes() { g_reporting = false; }
bool reporting_enabled() noexcept { return g_reporting; }

FatalSignalReport::FatalSignalReport(const Scene& scene, const std::vector<fs::path>& temp_files) {
  if (g_report.load() != nullptr) return;  // another run already reports (nested use)
  auto* r = new Report;
  const System& sys = *scene.system;
  for (const auto& f : sys.force_objects()) {
    r->entries.push_back({&f.label, describe("force", f.label, scene)});
  }
  for (const auto& c : sys.collider_objects()) {
    r->entries.push_back({&c.label, describe("collider", c.label, scene)});
  }
  r->entries.push_back({&scene.solver_label, describe("solver", scene.solver_label, scene)});
  for (const auto& w : scene.output.writers) {
    r->entries.push_back({&w.label, describe("writer", w.label, scene)});
  }
  for (const auto& p : temp_files) r->temp_files.push_back(p.string());
  r->removed_note =
      fmt::format("; its unfinished output was removed ({})", file_list(r->temp_files));
  r->installer_call = &t_current_call;
  g_step.store(0, std::memory_order_relaxed);

  r->alt_stack.resize(std::max<std::size_t>(SIGSTKSZ, 64 * 1024));
  stack_t ss{};
  ss.ss_sp = r->alt_stack.data();
  ss.ss_size = r->alt_stack.size();
  sigaltstack(&ss, &r->old_stack);

  g_report.store(r, std::memory_order_release);
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND | SA_ONSTACK;
  for (std::size_t k = 0; k < kSignalCount; ++k) {
    sigaction(kFatalSignals[k], &sa, &r->old_actions[k]);
  }
  installed_ = true;
}

FatalSignalReport::~FatalSignalReport() {
  if (!installed_) return;
  Report* r = g_report.load();
  for (std::size_t k = 0; k < kSignalCount; ++k) {
    sigaction(kFatalSignals[k], &r->old_actions[k], nullptr);
  }
  sigaltstack(&r->old_stack, nullptr);
  g_report.store(nullptr);
  delete r;
}

void FatalSignalReport::keep_temp_files(const fs::path& checkpoint) {
  if (!installed_) return;
  Report* r = g_report.load();
  if (r->keep.load() || r->temp_files.empty()) return;
  r->kept_note = fmt::format("; its unfinished output ({}) was kept for pdyn run --resume {}",
                             file_list(r->temp_files), checkpoint.string());
  r->keep.store(true, std::memory_order_release);
}

}  // namespace pdyn::crash
