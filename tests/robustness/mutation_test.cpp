// Mutation test: thousands of scenes made by mutating configs/ (deleted and
// duplicated lines, swapped types, huge, tiny, negative and non-finite
// numbers, deep nesting, unicode and invalid UTF-8, truncation) are run, each
// in its own folder and its own child process, by `pdyn run` for 3 steps.
// Each must exit 0, 2, 3 or 4: never a signal, never a hang, never an
// unclassified failure.
//
// The children are forked by pdyn_mutation_runner (mutation_runner.cpp) once
// it has opened the plugins, so that each mutant costs its run and not a
// program start; every 25th mutant is run again by the real `pdyn` program,
// which must end the same way.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <thread>

#include "support/test_support.hpp"

extern char** environ;

namespace pdyn {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// Replaces one number (or, failing that, one value after a colon) in `line`.
std::string replace_value(const std::string& line, const std::string& with, std::mt19937& rng) {
  static const std::regex number(R"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)");
  std::vector<std::pair<std::size_t, std::size_t>> spots;
  for (auto it = std::sregex_iterator(line.begin(), line.end(), number);
       it != std::sregex_iterator(); ++it) {
    spots.emplace_back(it->position(), it->length());
  }
  if (spots.empty()) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) return line + " " + with;
    return line.substr(0, colon + 1) + " " + with;
  }
  const auto [at, len] =
      spots[std::uniform_int_distribution<std::size_t>(0, spots.size() - 1)(rng)];
  return line.substr(0, at) + with + line.substr(at + len);
}

std::string mutate(std::vector<std::string> lines, std::mt19937& rng) {
  static const std::vector<std::string> values = {"1e308",
                                                  "-1e308",
                                                  "1e-320",
                                                  "0",
                                                  "-1",
                                                  "-0.5",
                                                  ".nan",
                                                  ".inf",
                                                  "-.inf",
                                                  "99999999999",
                                                  "abc",
                                                  "[1, 2]",
                                                  "[]",
                                                  "{}",
                                                  "{a: 1}",
                                                  "~",
                                                  "true",
                                                  "\"\"",
                                                  "[0, 0, 0]",
                                                  "2147483648",
                                                  "-9223372036854775809",
                                                  "1.5",
                                                  "\xc3\xa9\xe2\x98\x83",
                                                  "\xff\xfe",
                                                  "[[[[[[[[[[1]]]]]]]]]]",
                                                  "*anchor",
                                                  "&a [1, 2, 3]",
                                                  "!!binary aGVsbG8=",
                                                  "0x1F",
                                                  "1_000"};
  auto pick = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const int edits = 1 + static_cast<int>(pick(3));
  for (int e = 0; e < edits && !lines.empty(); ++e) {
    const std::size_t i = pick(lines.size());
    switch (pick(8)) {
      case 0:
        lines.erase(lines.begin() + static_cast<long>(i));
        break;
      case 1:
        lines.insert(lines.begin() + static_cast<long>(i), lines[i]);
        break;
      case 2:
      case 3:
        lines[i] = replace_value(lines[i], values[pick(values.size())], rng);
        break;
      case 4: {  // deep nesting
        const std::size_t depth = 50 + pick(5000);
        lines[i] =
            replace_value(lines[i], std::string(depth, '[') + "1" + std::string(depth, ']'), rng);
        break;
      }
      case 5:
        lines[i] = "  " + lines[i];
        break;  // indentation
      case 6:
        lines[i] = lines[i].substr(0, pick(lines[i].size() + 1));
        break;  // truncation
      case 7:
        std::swap(lines[i], lines[pick(lines.size())]);
        break;
    }
  }
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// A mutant's run is a hang after this long.
constexpr int kTimeoutSeconds = 60;

// Runs `PROGRAM ARGS` as a child process in `cwd`, its standard output on
// /dev/null and its standard error to `log`; returns its wait status, or -1
// if it had to be killed after `timeout`.
int run_child(const char* program, const std::vector<std::string>& args, const fs::path& cwd,
              std::chrono::seconds timeout, const fs::path& log = "/dev/null") {
  std::vector<char*> argv;
  std::vector<std::string> storage = args;
  storage.insert(storage.begin(), program);
  for (auto& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const fs::path old = fs::current_path();
  fs::current_path(cwd);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, program, &actions, nullptr, argv.data(), environ);
  fs::current_path(old);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -2;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return status;
}

// "exit 2" or "signal 11" for a wait status.
std::string outcome(int status) {
  if (status == -1) return "hang (killed after " + std::to_string(kTimeoutSeconds) + " s)";
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "exit " + std::to_string(WEXITSTATUS(status));
}

TEST(Mutation, MutatedConfigsNeverCrashOrHang) {
  const char* env = std::getenv("PDYN_MUTATIONS");
  const int count = env ? std::atoi(env) : 2000;
  std::vector<std::vector<std::string>> sources;
  for (const auto& e : fs::directory_iterator(test::source_path("configs"))) {
    if (e.path().extension() == ".yaml") sources.push_back(read_lines(e.path()));
  }
  ASSERT_FALSE(sources.empty());
  std::sort(sources.begin(), sources.end());  // the same mutants whatever the folder's order
  const fs::path dir = test::temp_dir("mutation");
  std::mt19937 rng(20261122);
  std::vector<std::string> texts;
  std::string list;
  for (int n = 0; n < count; ++n) {
    texts.push_back(mutate(sources[static_cast<std::size_t>(n) % sources.size()], rng));
    const fs::path folder = dir / std::to_string(n);
    test::write_file(folder / "mutant.yaml", texts.back());
    list += folder.string() + "\n";
  }
  test::write_file(dir / "list.txt", list);
  const int runner = run_child(PDYN_MUTATION_RUNNER,
                               {(dir / "list.txt").string(), (dir / "results.txt").string(),
                                std::to_string(kTimeoutSeconds)},
                               dir, std::chrono::seconds(3600), dir / "runner.log");
  ASSERT_TRUE(WIFEXITED(runner) && WEXITSTATUS(runner) == 0)
      << "pdyn_mutation_runner failed: " << outcome(runner) << "\n"
      << test::read_bytes(dir / "runner.log");
  std::vector<int> statuses;
  for (const auto& line : test::split_lines(test::read_bytes(dir / "results.txt"))) {
    statuses.push_back(std::stoi(line));
  }
  ASSERT_EQ(statuses.size(), texts.size());

  std::map<int, int> outcomes;
  for (int n = 0; n < count; ++n) {
    const int status = statuses[static_cast<std::size_t>(n)];
    const std::string& text = texts[static_cast<std::size_t>(n)];
    ASSERT_TRUE(WIFEXITED(status)) << outcome(status) << " on mutant " << n << ":\n" << text;
    const int code = WEXITSTATUS(status);
    ASSERT_TRUE(code == 0 || code == 2 || code == 3 || code == 4)
        << "exit " << code << " on mutant " << n << ":\n"
        << text;
    ++outcomes[code];
  }
  // The program itself, on every 25th mutant in a fresh folder of its own,
  // ends as the forked child did.
  for (int n = 0; n < count; n += 25) {
    const fs::path folder = dir / (std::to_string(n) + "-program");
    test::write_file(folder / "mutant.yaml", texts[static_cast<std::size_t>(n)]);
    const int status = run_child(PDYN_BIN, {"run", "mutant.yaml", "--steps", "3", "--quiet"},
                                 folder, std::chrono::seconds(kTimeoutSeconds));
    ASSERT_NE(status, -2) << "could not start " << PDYN_BIN;
    EXPECT_EQ(outcome(status), outcome(statuses[static_cast<std::size_t>(n)]))
        << "the pdyn program and the forked run disagree on mutant " << n << ":\n"
        << texts[static_cast<std::size_t>(n)];
  }
  std::cout << "mutation test: " << count << " mutants; exit 0: " << outcomes[0]
            << ", exit 2: " << outcomes[2] << ", exit 3: " << outcomes[3]
            << ", exit 4: " << outcomes[4] << "\n";
  // The mutants must exercise both the accepting and the refusing paths.
  EXPECT_GT(outcomes[0], count / 20);
  EXPECT_GT(outcomes[2], count / 4);
}

}  // namespace
}  // namespace pdyn
