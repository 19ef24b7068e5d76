// Malformed scenes: every file in tests/scenes/bad/ is a scene with a known
// problem, and states on its first line what `pdyn validate` must report:
//
//   # expect: status=2 line=7 column=5 contains="did you mean 'mass'" errors=1
//   # also: line=9 contains="..."
//
// `# expect:` describes the exit status and the first line of stderr; each
// `# also:` line describes the next line of stderr, in order. Keys:
//   status=N        exit status (required)
//   line=N          the line starts with `FILE:N:` (FILE as given on the command line)
//   column=N        ... and with `FILE:LINE:N:`
//   location="..."  the line starts with `...: ` instead (a --set override, say)
//   contains="..."  the line contains this text (repeatable)
//   args="..."      extra arguments after FILE, split at spaces
//   errors=N        stderr has exactly N lines (default: not checked)
// Either line= or location= is required: every scene problem has a place.
// Values are double-quoted if they contain spaces; no escapes.
//
// The contract: every scene problem is reported as `FILE:LINE:COLUMN: what is
// wrong (what was expected)` with exit status 2, before any simulation starts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

struct LineExpectation {
  std::optional<int> line, column;
  std::optional<std::string> location;
  std::vector<std::string> contains;
};

struct Expectation {
  int status = -1;
  std::vector<std::string> args;
  std::optional<std::size_t> errors;
  std::vector<LineExpectation> lines;  // [0]: the `# expect:` line
};

// Parses `key=value key="value with spaces" ...`; throws on malformed text.
std::vector<std::pair<std::string, std::string>> parse_pairs(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t i = 0;
  while (i < text.size()) {
    if (text[i] == ' ') {
      ++i;
      continue;
    }
    const auto eq = text.find('=', i);
    if (eq == std::string::npos) throw std::runtime_error("no '=' after key in: " + text);
    std::string key = text.substr(i, eq - i);
    std::string value;
    if (eq + 1 < text.size() && text[eq + 1] == '"') {
      const auto close = text.find('"', eq + 2);
      if (close == std::string::npos) throw std::runtime_error("unclosed '\"' in: " + text);
      value = text.substr(eq + 2, close - eq - 2);
      i = close + 1;
    } else {
      const auto end = text.find(' ', eq + 1);
      value = text.substr(eq + 1, end == std::string::npos ? std::string::npos : end - eq - 1);
      i = end == std::string::npos ? text.size() : end;
    }
    out.emplace_back(std::move(key), std::move(value));
  }
  return out;
}

Expectation read_expectation(const fs::path& file) {
  std::ifstream in(file);
  std::string text;
  Expectation e;
  bool first = true;
  while (std::getline(in, text)) {
    const std::string expect = "# expect:", also = "# also:";
    const bool is_expect = first && text.rfind(expect, 0) == 0;
    const bool is_also = !first && text.rfind(also, 0) == 0;
    if (first && !is_expect) {
      throw std::runtime_error(file.string() + ": the first line is not '# expect: ...'");
    }
    if (!is_expect && !is_also) break;
    first = false;
    LineExpectation le;
    for (const auto& [key, value] : parse_pairs(text.substr((is_expect ? expect : also).size()))) {
      if (key == "status" && is_expect)
        e.status = std::stoi(value);
      else if (key == "errors" && is_expect)
        e.errors = std::stoul(value);
      else if (key == "args" && is_expect) {
        std::istringstream words(value);
        for (std::string w; words >> w;) e.args.push_back(w);
      } else if (key == "line")
        le.line = std::stoi(value);
      else if (key == "column")
        le.column = std::stoi(value);
      else if (key == "location")
        le.location = value;
      else if (key == "contains")
        le.contains.push_back(value);
      else
        throw std::runtime_error(file.string() + ": unknown expectation key '" + key + "'");
    }
    if (!le.line && !le.location) {
      throw std::runtime_error(file.string() + ": each expectation needs line= or location=");
    }
    e.lines.push_back(std::move(le));
  }
  if (e.status < 0) throw std::runtime_error(file.string() + ": no status= in '# expect:'");
  return e;
}

fs::path bad_dir() { return test::source_path("tests/scenes/bad"); }

std::vector<std::string> bad_scenes() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(bad_dir())) {
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The shipped plugins only: an inherited $PDYN_PLUGIN_PATH must not add
// warnings in front of the diagnostics.
class MalformedScene : public testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (const char* env = std::getenv("PDYN_PLUGIN_PATH")) saved_ = env;
    ::unsetenv("PDYN_PLUGIN_PATH");
  }
  void TearDown() override {
    if (saved_) ::setenv("PDYN_PLUGIN_PATH", saved_->c_str(), 1);
  }

  // Checks `result` against the expectation of `file`.
  void check(const fs::path& file, const Expectation& e, const test::CommandResult& r) {
    EXPECT_EQ(r.status, e.status) << "stderr:\n" << r.err;
    const auto lines = test::split_lines(r.err);
    if (e.errors) {
      EXPECT_EQ(lines.size(), *e.errors) << "stderr:\n" << r.err;
    }
    ASSERT_GE(lines.size(), e.lines.size()) << "stderr:\n" << r.err;
    const std::string quoted =
        std::regex_replace(file.string(), std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)");
    const std::regex located("^" + quoted + R"(:(\d+):(\d+): \S)");
    for (std::size_t k = 0; k < e.lines.size(); ++k) {
      const LineExpectation& le = e.lines[k];
      const std::string& line = lines[k];
      SCOPED_TRACE("stderr line " + std::to_string(k + 1) + ": " + line);
      if (le.location) {
        EXPECT_EQ(line.rfind(*le.location + ": ", 0), 0u) << "expected location " << *le.location;
      } else {
        std::smatch m;
        ASSERT_TRUE(std::regex_search(line, m, located)) << "expected FILE:LINE:COLUMN: ...";
        EXPECT_EQ(std::stoi(m[1]), *le.line) << "line";
        if (le.column) {
          EXPECT_EQ(std::stoi(m[2]), *le.column) << "column";
        }
      }
      for (const auto& text : le.contains) {
        EXPECT_NE(line.find(text), std::string::npos) << "expected to contain: " << text;
      }
    }
  }

 private:
  std::optional<std::string> saved_;
};

TEST_P(MalformedScene, ValidateReportsTheProblemWithItsPlace) {
  const fs::path file = bad_dir() / GetParam();
  const Expectation e = read_expectation(file);
  std::vector<std::string> args{"validate", file.string()};
  args.insert(args.end(), e.args.begin(), e.args.end());
  const auto r = test::pdyn(args);
  check(file, e, r);
  EXPECT_EQ(r.out, "") << "validate printed a result for a bad scene";
}

// `pdyn run` refuses the same scenes with the same report, before stepping.
TEST_P(MalformedScene, RunRefusesItTheSameWay) {
  const fs::path file = bad_dir() / GetParam();
  const Expectation e = read_expectation(file);
  std::vector<std::string> args{"run", file.string()};
  args.insert(args.end(), e.args.begin(), e.args.end());
  const auto r = test::pdyn(args);
  check(file, e, r);
  EXPECT_EQ(r.out, "");
}

std::string test_name(const testing::TestParamInfo<std::string>& info) {
  std::string name = fs::path(info.param).stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(BadScenes, MalformedScene, testing::ValuesIn(bad_scenes()), test_name);

// The folder must hold the cases the contract names; a rename that drops one
// should be noticed.
TEST(MalformedScenes, FolderHoldsAtLeastTwentyCases) { EXPECT_GE(bad_scenes().size(), 20u); }

TEST(MalformedScenes, TwoIndependentErrorsAreBothReported) {
  const fs::path dir = test::temp_dir("two-errors");
  const fs::path scene = test::write_file(dir / "scene.yaml", R"(simulation:
  dt: 0.01
  steps: 10
particles:
  - { position: [0, 0, 1], mass: 1 }
  - { position: [1, 0], mass: 1 }
forces:
  - { type: gravity, g: [0, 0, .inf] }
)");
  const auto r = test::pdyn({"validate", scene.string()});
  EXPECT_EQ(r.status, 2);
  const auto lines = test::split_lines(r.err);
  ASSERT_EQ(lines.size(), 2u) << r.err;
  EXPECT_EQ(lines[0].rfind(scene.string() + ":6:17: particles[1].position: is not a 3-vector", 0),
            0u)
      << lines[0];
  EXPECT_EQ(lines[1].rfind(scene.string() + ":8:32: forces[0].g[2]: .inf is not finite", 0), 0u)
      << lines[1];
}

TEST(MalformedScenes, RunOnABadSceneExitsTwoAndWritesNoOutput) {
  const fs::path dir = test::temp_dir("bad-run");
  const fs::path frames = dir / "out" / "frames.csv", energy = dir / "out" / "energy.csv";
  const fs::path scene = test::write_file(dir / "scene.yaml",
                                          "simulation: { dt: 0.01, steps: 10 }\n"
                                          "particles:\n"
                                          "  - { position: [0, 0, 1], mass: -1 }\n"
                                          "output:\n"
                                          "  path: " +
                                              frames.string() +
                                              "\n"
                                              "  energy: " +
                                              energy.string() + "\n");
  const auto r = test::pdyn({"run", scene.string()});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.rfind(scene.string() + ":3:34: particles[0].mass: -1 is out of range", 0), 0u)
      << r.err;
  EXPECT_FALSE(fs::exists(frames));
  EXPECT_FALSE(fs::exists(energy));
  EXPECT_FALSE(fs::exists(dir / "out")) << "no output folder either";
  // Nothing but the scene itself, not even a temporary file.
  std::vector<fs::path> left;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) left.push_back(entry.path());
  EXPECT_EQ(left, std::vector<fs::path>{scene});
}

// The same refusal through --set: the location names the override.
TEST(MalformedScenes, RunWithABadOverrideWritesNoOutput) {
  const fs::path dir = test::temp_dir("bad-run-set");
  const fs::path frames = dir / "frames.csv";
  const fs::path scene = test::write_file(dir / "scene.yaml",
                                          "simulation: { dt: 0.01, steps: 10 }\n"
                                          "particles:\n"
                                          "  - { position: [0, 0, 1], mass: 1 }\n");
  const auto r = test::pdyn({"run", scene.string(), "--set", "output.path=" + frames.string(),
                             "--set", "simulation.dt=nan"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.rfind("--set simulation.dt=nan: simulation.dt: 'nan' is not a number", 0), 0u)
      << r.err;
  EXPECT_FALSE(fs::exists(frames));
}

// `--set output=~` in bash arrives as `output=$HOME`: the refusal says so.
TEST(MalformedScenes, SetValueThatIsTheExpandedHomeFolderSuggestsNull) {
  const char* saved = std::getenv("HOME");
  const std::string old_home = saved ? saved : "";
  ::setenv("HOME", "/home/pdyn-tester", 1);
  const fs::path dir = test::temp_dir("set-home");
  const fs::path scene = test::write_file(dir / "scene.yaml",
                                          "simulation: { dt: 0.01, steps: 3 }\n"
                                          "particles:\n"
                                          "  - { position: [0, 0, 1], mass: 1 }\n");
  const auto r =
      test::pdyn({"validate", scene.string(), "--set", "simulation.steps=/home/pdyn-tester",
                  "--set", "output=/home/pdyn-tester/x"});
  const auto fine = test::pdyn(
      {"validate", scene.string(), "--quiet", "--set", "output.path=/home/pdyn-tester/out.csv"});
  if (saved) {
    ::setenv("HOME", old_home.c_str(), 1);
  } else {
    ::unsetenv("HOME");
  }
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "--set simulation.steps=/home/pdyn-tester: simulation.steps: '/home/pdyn-tester' is "
            "not a whole number (did you mean null? the shell expands ~ to your home folder; "
            "expected a whole number >= 0)\n"
            "--set output=/home/pdyn-tester/x: output: '/home/pdyn-tester/x' is not a mapping "
            "(did you mean null? the shell expands ~ to your home folder; expected output: a "
            "list of writers, e.g. - { type: csv, path: FILE.csv, every: N }, or { path: "
            "FILE.csv, every: N, energy: FILE.csv })\n");
  // A path key takes a path in the home folder without comment.
  EXPECT_EQ(fine.status, 0) << fine.err;
}

// A --set into a section the scene does not have creates it.
TEST(MalformedScenes, SetCreatesAMissingSection) {
  const fs::path dir = test::temp_dir("set-output");
  const fs::path frames = dir / "frames.csv";
  const fs::path scene = test::write_file(dir / "scene.yaml",
                                          "simulation: { dt: 0.01, steps: 3 }\n"
                                          "particles:\n"
                                          "  - { position: [0, 0, 1], mass: 1 }\n");
  const auto r =
      test::pdyn({"run", scene.string(), "--quiet", "--set", "output.path=" + frames.string()});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(frames));
}

}  // namespace
}  // namespace pdyn
