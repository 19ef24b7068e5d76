// Interrupts: the real `pdyn` binary (PDYN_BIN) runs a 256-particle sheet
// in a child process and is sent signals.
//
//  * SIGINT / SIGTERM once: exit status 130; stderr is one line holding
//    "interrupted at step K" and the command that resumes; the frames and
//    energy files exist under their final names, complete (whole frames of
//    8-field rows, the last one at step K); a checkpoint at step K exists
//    beside the frames; no temporary file is left. Running the printed
//    command finishes the run, and its output files are byte-identical to
//    an uninterrupted run's.
//  * Two signals: the process exits promptly with 130, and no file under a
//    final name is half-written. Made deterministic by stopping the child
//    (SIGSTOP), queueing SIGINT and SIGTERM, and continuing it: the second
//    handler runs before the interrupted step can finish, so no final file
//    may exist at all. A quick SIGINT pair without the stop is also sent;
//    there the first may be handled before the second arrives, so final
//    files may exist, but only complete ones.
#include <gtest/gtest.h>

#include "host/resume_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

constexpr int kSide = 16, kSignalParticles = kSide * kSide;
constexpr double kSignalDt = 0.001;

// The words of a command line printed for a POSIX shell ('...' quoting).
std::vector<std::string> shell_words(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false, quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '\'')
        quoted = false;
      else
        word += c;
    } else if (c == '\'') {
      quoted = in_word = true;
    } else if (c == '\\' && i + 1 < line.size()) {
      word += line[++i];
      in_word = true;
    } else if (c == ' ') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

bool output_started(const fs::path& dir) {
  return !files_starting(dir / "out", "frames.csv.tmp-").empty();
}

// Last line's fields of a CSV file.
std::vector<std::string> last_row(const fs::path& p) {
  const auto lines = lines_of(read_bytes(p));
  std::vector<std::string> fields;
  if (lines.empty()) return fields;
  std::istringstream row(lines.back());
  for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
  return fields;
}

void interrupt_and_resume(int sig, const std::string& name) {
  const fs::path dir = temp_dir("signal-" + name), ref = temp_dir("signal-ref-" + name);
  // No checkpoint section: an interrupted run still writes one, beside the frames.
  const std::string scene = sheet_scene("rk4", /*every=*/50, /*ckpt_every=*/-1, kSignalDt, kSide);
  write_file(dir / "scene.yaml", scene);
  write_file(ref / "scene.yaml", scene);
  // The signal is sent as soon as the run has started; should the test be
  // held up so long that the run finished first, it is tried again longer.
  std::int64_t total = 1500;
  int status = 0;
  std::string err;
  for (int attempt = 0;; ++attempt, total *= 4) {
    fs::remove_all(dir / "out");
    Child child({"run", "scene.yaml", "--steps", std::to_string(total), "-q"}, dir);
    ASSERT_TRUE(wait_until([&] { return output_started(dir) || !child.running(); },
                           std::chrono::seconds(20)));
    child.signal(sig);
    ASSERT_TRUE(child.wait(std::chrono::seconds(60))) << "no exit 60 s after " << name;
    status = child.status();
    err = child.err();
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0) || attempt == 2) break;
  }
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  ASSERT_EQ(WEXITSTATUS(status), 130) << err;

  // One line: the step reached and the command that resumes.
  const auto lines = lines_of(err);
  ASSERT_EQ(lines.size(), 1u) << err;
  const std::string& line = lines[0];
  EXPECT_TRUE(contains(line, "interrupted at step ")) << line;
  EXPECT_TRUE(contains(line, "--resume")) << line;
  const auto at = line.find("interrupted at step ");
  ASSERT_NE(at, std::string::npos);
  const std::int64_t k = std::stoll(line.substr(at + 20));
  ASSERT_GT(k, 0) << line;
  ASSERT_LT(k, total) << line;
  const double t_k = static_cast<double>(k) * kSignalDt;

  // Complete files under their final names, ending at step k.
  double last_t = -1;
  const int frames = check_frames_file(dir / "out/frames.csv", kSignalParticles, &last_t);
  EXPECT_EQ(frames, static_cast<int>(k / 50) + 1 + (k % 50 != 0))
      << "frames at 0, every 50 steps, and at " << k;
  EXPECT_EQ(last_t, t_k);
  const auto energy = last_row(dir / "out/energy.csv");
  ASSERT_EQ(energy.size(), 4u);
  EXPECT_EQ(std::stod(energy[0]), t_k);
  EXPECT_EQ(read_bytes(dir / "out/energy.csv").back(), '\n');
  ASSERT_TRUE(fs::exists(dir / "out/frames.ckpt"));
  const Checkpoint c = read_checkpoint(dir / "out/frames.ckpt");
  EXPECT_EQ(c.step, k);
  EXPECT_EQ(c.time, t_k);
  EXPECT_TRUE(c.state.allFinite());
  EXPECT_TRUE(contains(line, "--resume out/frames.ckpt")) << line;
  for (const char* prefix : {"frames.csv.tmp-", "energy.csv.tmp-", "frames.ckpt.tmp-"}) {
    EXPECT_TRUE(files_starting(dir / "out", prefix).empty()) << prefix << "* left behind";
  }

  // The printed command finishes the run, as if it had never stopped.
  auto words = shell_words(line.substr(line.find("resume with: ") + 13));
  ASSERT_GE(words.size(), 3u);
  ASSERT_EQ(words[0], "pdyn");
  words.erase(words.begin());
  auto resumed = pdyn_in(dir, words);
  ASSERT_EQ(resumed.status, 0) << resumed.err;
  auto whole = pdyn_in(ref, {"run", "scene.yaml", "--steps", std::to_string(total), "-q"});
  ASSERT_EQ(whole.status, 0) << whole.err;
  for (const char* f : {"out/frames.csv", "out/energy.csv"}) {
    EXPECT_TRUE(read_bytes(dir / f) == read_bytes(ref / f))
        << f << " differs from the uninterrupted run's";
  }
  EXPECT_EQ(check_frames_file(dir / "out/frames.csv", kSignalParticles),
            static_cast<int>(total / 50) + 1);
}

TEST(Signals, SigintStopsCleanlyAndResumes) { interrupt_and_resume(SIGINT, "SIGINT"); }

TEST(Signals, SigtermStopsCleanlyAndResumes) { interrupt_and_resume(SIGTERM, "SIGTERM"); }

char process_state(pid_t pid) {
  const std::string stat = read_bytes("/proc/" + std::to_string(pid) + "/stat");
  const auto close = stat.rfind(')');
  return close == std::string::npos || close + 2 >= stat.size() ? '?' : stat[close + 2];
}

TEST(Signals, SecondSignalExitsAtOnceLeavingNoFinalFile) {
  const fs::path dir = temp_dir("signal-double");
  write_file(dir / "scene.yaml", sheet_scene("rk4", 50, -1, kSignalDt, kSide));
  Child child({"run", "scene.yaml", "--steps", "1000000", "-q"}, dir);
  ASSERT_TRUE(wait_until([&] { return output_started(dir) || !child.running(); },
                         std::chrono::seconds(20)));
  ASSERT_TRUE(child.running()) << child.err();
  child.signal(SIGSTOP);
  ASSERT_TRUE(
      wait_until([&] { return process_state(child.pid()) == 'T'; }, std::chrono::seconds(10)));
  child.signal(SIGINT);
  child.signal(SIGTERM);
  const auto sent = std::chrono::steady_clock::now();
  child.signal(SIGCONT);
  ASSERT_TRUE(child.wait(std::chrono::seconds(5))) << "still running 5 s after two signals";
  EXPECT_LT(std::chrono::steady_clock::now() - sent, std::chrono::seconds(2));
  ASSERT_TRUE(WIFEXITED(child.status())) << "killed by signal " << WTERMSIG(child.status());
  EXPECT_EQ(WEXITSTATUS(child.status()), 130);
  // Nothing under a final name: the run was in the middle of a step.
  for (const char* f : {"frames.csv", "energy.csv", "frames.ckpt"}) {
    EXPECT_FALSE(fs::exists(dir / "out" / f)) << f << " exists after an immediate exit";
  }
}

TEST(Signals, QuickSigintPairLeavesOnlyCompleteFiles) {
  const fs::path dir = temp_dir("signal-pair");
  write_file(dir / "scene.yaml", sheet_scene("rk4", 50, -1, kSignalDt, kSide));
  Child child({"run", "scene.yaml", "--steps", "1000000", "-q"}, dir);
  ASSERT_TRUE(wait_until([&] { return output_started(dir) || !child.running(); },
                         std::chrono::seconds(20)));
  ASSERT_TRUE(child.running()) << child.err();
  child.signal(SIGINT);
  child.signal(SIGINT);
  const auto sent = std::chrono::steady_clock::now();
  ASSERT_TRUE(child.wait(std::chrono::seconds(5))) << "still running 5 s after two signals";
  EXPECT_LT(std::chrono::steady_clock::now() - sent, std::chrono::seconds(2));
  ASSERT_TRUE(WIFEXITED(child.status())) << "killed by signal " << WTERMSIG(child.status());
  EXPECT_EQ(WEXITSTATUS(child.status()), 130);
  // Whatever exists under a final name is complete.
  if (fs::exists(dir / "out/frames.csv")) {
    EXPECT_GE(check_frames_file(dir / "out/frames.csv", kSignalParticles), 2);
  }
  if (fs::exists(dir / "out/energy.csv")) {
    const std::string e = read_bytes(dir / "out/energy.csv");
    EXPECT_EQ(e.back(), '\n');
    for (const auto& l : lines_of(e)) EXPECT_EQ(std::count(l.begin(), l.end(), ','), 3) << l;
  }
  if (fs::exists(dir / "out/frames.ckpt")) {
    EXPECT_NO_THROW(read_checkpoint(dir / "out/frames.ckpt"));
  }
}

}  // namespace
}  // namespace pdyn
