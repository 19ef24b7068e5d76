// Plugins that crash or hang, with the fixture plugins of tests/fixtures/
// (folder crash/, loaded with --plugin-path), run in the real `pdyn`
// binary (PDYN_BIN) as a child process:
//   crashing_force   add_forces writes through a null pointer after `after` calls
//   hanging_force    add_forces never returns
//
//  * `pdyn check` runs the checks in a child process: a check that crashes
//    fails "crashed with SIGSEGV", one that hangs fails "timed out after S s",
//    the other checks still run, the exit status is the kit's failure (1)
//    and the JUnit file records it. A healthy plugin's report is the same
//    isolated as in-process (--in-process).
//  * `pdyn run` dies of the signal (status 128 + 11) after one stderr line
//    naming the force, its library, the call and the step, and leaves no
//    temporary output file, unless a checkpoint was written, which the
//    temporary files then continue: they are kept and named.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/test_support.hpp"

extern char** environ;

namespace pdyn {
namespace {

namespace fs = std::filesystem;

const std::string kCrashDir = std::string(PDYN_FIXTURE_DIR) + "/crash";

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::size_t count_of(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

// The table row of check `name` ("" if none).
std::string row_of(const std::string& report, const std::string& name) {
  for (const auto& l : lines_of(report)) {
    if (l.rfind(name + " ", 0) == 0) return l;
  }
  return "";
}

struct CrashOutcome {
  int shell_status = -1;  // as a shell reports it: the exit status, or 128 + signal
  std::string out, err;
};

// Runs PDYN_BIN with `args` in `cwd`, stdout and stderr captured, and waits
// at most `limit` (then kills it: a test must not hang with the plugin).
CrashOutcome run_pdyn(const std::vector<std::string>& args, const fs::path& cwd,
                      std::chrono::seconds limit = std::chrono::seconds(120)) {
  std::vector<std::string> words = args;
  words.insert(words.begin(), PDYN_BIN);
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  const fs::path out = cwd / "pdyn.out", err = cwd / "pdyn.err";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const fs::path old = fs::current_path();
  fs::current_path(cwd);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, PDYN_BIN, &actions, nullptr, argv.data(), environ);
  fs::current_path(old);
  posix_spawn_file_actions_destroy(&actions);
  CrashOutcome o;
  if (rc != 0) {
    ADD_FAILURE() << "cannot start " << PDYN_BIN;
    return o;
  }
  const auto deadline = std::chrono::steady_clock::now() + limit;
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "pdyn did not end within " << limit.count() << " s";
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  o.shell_status = WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
  o.out = read_text(out);
  o.err = read_text(err);
  return o;
}

TEST(PluginCrash, CheckFailsTheChecksThatCrashAndRunsTheOthers) {
  const fs::path dir = test::temp_dir("crash-check");
  const fs::path junit = dir / "report.xml";
  const auto r = run_pdyn(
      {"check", "crashing_force", "--plugin-path", kCrashDir, "--junit", junit.string()}, dir);
  // The kit's "a check failed", not the 139 of a process killed by SIGSEGV.
  EXPECT_EQ(r.shell_status, 1) << r.out << r.err;
  // Every check that calls add_forces crashed; each is named with the signal.
  for (const char* check : {"deterministic", "read_only_state", "adds_only", "finite_on_degenerate",
                            "threads.two_systems"}) {
    const std::string row = row_of(r.out, check);
    EXPECT_TRUE(has(row, "FAIL") && has(row, "crashed with SIGSEGV")) << check << ":\n" << r.out;
  }
  // The others still ran, after the crashes too.
  for (const char* check : {"descriptor.complete", "construct.defaults", "params.bad_rejected"}) {
    EXPECT_TRUE(has(row_of(r.out, check), "pass")) << check << ":\n" << r.out;
  }
  EXPECT_TRUE(has(row_of(r.out, "force.net_force_zero"), "skip")) << r.out;
  EXPECT_TRUE(has(r.out,
                  "5 check(s) failed: deterministic, read_only_state, adds_only, "
                  "finite_on_degenerate, threads.two_systems"))
      << r.out;
  // The JUnit file records the same.
  ASSERT_TRUE(fs::exists(junit)) << r.out << r.err;
  const std::string xml = read_text(junit);
  EXPECT_TRUE(has(xml, "failures=\"5\"")) << xml;
  EXPECT_EQ(count_of(xml, "crashed with SIGSEGV"), 5u) << xml;
  EXPECT_TRUE(has(xml,
                  "name=\"deterministic\">\n    <failure message=\"measured 0, bound 0: "
                  "crashed with SIGSEGV\"/>"))
      << xml;
  EXPECT_TRUE(has(xml, "name=\"params.bad_rejected\"/>")) << xml;
}

TEST(PluginCrash, CheckTimesOutAHangingCheck) {
  const fs::path dir = test::temp_dir("crash-hang");
  const auto start = std::chrono::steady_clock::now();
  const auto r =
      run_pdyn({"check", "hanging_force", "--plugin-path", kCrashDir, "--timeout", "0.3"}, dir);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.shell_status, 1) << r.out << r.err;
  const std::string row = row_of(r.out, "deterministic");
  EXPECT_TRUE(has(row, "FAIL") && has(row, "timed out after 0.3 s")) << r.out;
  EXPECT_EQ(count_of(r.out, "timed out after 0.3 s"), 5u) << r.out;
  EXPECT_TRUE(has(row_of(r.out, "params.bad_rejected"), "pass")) << r.out;
  // Five hung checks of 0.3 s each, and the rest quick: not the 10 s default.
  EXPECT_LT(took, 8.0) << r.out;
}

TEST(PluginCrash, IsolatedReportIsTheInProcessReport) {
  const fs::path dir = test::temp_dir("crash-same");
  for (const char* plugin : {"spring", "rk4", "plane"}) {
    const auto isolated = run_pdyn({"check", plugin}, dir);
    const auto in_process = run_pdyn({"check", plugin, "--in-process"}, dir);
    EXPECT_EQ(isolated.shell_status, 0) << isolated.out << isolated.err;
    EXPECT_EQ(isolated.out, in_process.out) << plugin;
  }
}

// A scene with one particle falling under gravity, stepped by explicit
// Euler (one force evaluation per step), with crashing_force: its call
// `after` + 1, the one that crashes, is made in step `after` + 1.
std::string crash_scene(int after, const std::string& checkpoint = "") {
  return "simulation:\n"
         "  dt: 0.01\n"
         "  steps: 50\n"
         "  solver: { type: euler }\n"
         "output:\n"
         "  path: out/frames.csv\n"
         "  every: 1\n"
         "  energy: out/energy.csv\n" +
         checkpoint +
         "particles:\n"
         "  - { position: [0, 0, 1], velocity: [0.5, 0, 0], mass: 0.1 }\n"
         "forces:\n"
         "  - { type: gravity, g: [0, 0, -9.81] }\n"
         "  - { type: crashing_force, after: " +
         std::to_string(after) + " }\n";
}

std::vector<fs::path> temp_files_in(const fs::path& dir) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (has(e.path().filename().string(), ".tmp-")) found.push_back(e.path());
  }
  return found;
}

TEST(PluginCrash, RunNamesThePluginAndDiesOfTheSignal) {
  const fs::path dir = test::temp_dir("crash-run");
  test::write_file(dir / "scene.yaml", crash_scene(11));
  const auto r = run_pdyn({"run", "scene.yaml", "-q", "--plugin-path", kCrashDir}, dir);
  EXPECT_EQ(r.shell_status, 128 + SIGSEGV) << r.err;
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.err;
  const std::string& line = lines[0];
  EXPECT_TRUE(has(line, "pdyn: force 'crashing_force' (scene.yaml:")) << line;
  EXPECT_TRUE(has(line, "library " + kCrashDir + "/pdyn_force_crashing_force.so")) << line;
  EXPECT_TRUE(has(line, "crashed with SIGSEGV in add_forces at step 12")) << line;
  EXPECT_TRUE(has(line, "unfinished output was removed")) << line;
  EXPECT_TRUE(temp_files_in(dir / "out").empty()) << line;
  EXPECT_TRUE(temp_files_in(dir).empty()) << line;
}

TEST(PluginCrash, RunKeepsTheTemporaryOutputACheckpointContinues) {
  const fs::path dir = test::temp_dir("crash-run-ckpt");
  test::write_file(dir / "scene.yaml",
                   crash_scene(11, "  checkpoint: { path: out/run.ckpt, every: 5 }\n"));
  const auto r = run_pdyn({"run", "scene.yaml", "-q", "--plugin-path", kCrashDir}, dir);
  EXPECT_EQ(r.shell_status, 128 + SIGSEGV) << r.err;
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_TRUE(has(lines[0], "crashed with SIGSEGV in add_forces at step 12")) << lines[0];
  EXPECT_TRUE(has(lines[0], "was kept for pdyn run --resume out/run.ckpt")) << lines[0];
  // Both files, named in the line, still there for the resume.
  const auto kept = temp_files_in(dir / "out");
  EXPECT_EQ(kept.size(), 2u) << lines[0];
  for (const auto& f : kept) EXPECT_TRUE(has(lines[0], f.filename().string())) << lines[0];
}

}  // namespace
}  // namespace pdyn
