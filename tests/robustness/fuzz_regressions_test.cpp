// The fuzzer's regression corpus, tests/robustness/fuzz_regressions/: every file there
// is a scene input that fuzzing hit or might hit (deep nesting, alias bombs,
// long strings, control bytes, ...). Each is checked the way the fuzz
// target reads it -- its "#set KEY=VALUE" lines are applied as --set
// overrides -- with `pdyn validate` run in-process: it must exit 0 or 2,
// never crash, hang or fail otherwise. scripts/fuzz.sh seeds the fuzzer
// with the folder, so its files stay under libFuzzer's default maximum input
// length (4 KiB; a bigger seed would raise it for the whole run); inputs too
// big for that (a 10 MB string) are generated here instead.
#include <gtest/gtest.h>

#include "host/resume_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

// `pdyn validate FILE` with the file's "#set " lines as --set overrides.
CommandResult validate(const fs::path& file) {
  std::vector<std::string> args = {"validate", file.string(), "--quiet"};
  std::istringstream lines(read_bytes(file));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("#set ", 0) == 0) {
      args.push_back("--set");
      args.push_back(line.substr(5));
    }
  }
  return pdyn(args);
}

TEST(FuzzRegressions, EveryInputIsAcceptedOrRefused) {
  const fs::path corpus = source_path("tests/robustness/fuzz_regressions");
  int count = 0;
  for (const auto& e : fs::directory_iterator(corpus)) {
    if (!e.is_regular_file()) continue;
    SCOPED_TRACE(e.path().filename().string());
    const auto started = std::chrono::steady_clock::now();
    const CommandResult r = validate(e.path());
    EXPECT_TRUE(r.status == 0 || r.status == 2)
        << "exit " << r.status << ": " << r.err.substr(0, 2000);
    if (r.status == 2) {
      EXPECT_FALSE(r.err.empty()) << "refused without saying why";
    }
    EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(10));
    ++count;
  }
  EXPECT_GE(count, 3) << "the corpus in " << corpus << " is missing";
}

TEST(FuzzRegressions, CorpusOutcomes) {
  // The inputs committed with this test, and what each must give: the
  // overrides make the otherwise valid scene invalid.
  const fs::path corpus = source_path("tests/robustness/fuzz_regressions");
  for (const char* name :
       {"deep_flow_nesting.yaml", "deep_map_nesting.yaml", "override_deep_nesting.yaml",
        "long_strings.yaml", "alias_bomb.yaml", "control_bytes.yaml"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(fs::exists(corpus / name));
    EXPECT_EQ(validate(corpus / name).status, 2);
  }
  // Without its overrides the override scene is valid.
  EXPECT_EQ(pdyn({"validate", (corpus / "override_deep_nesting.yaml").string(), "-q"}).status, 0);
}

TEST(FuzzRegressions, TenMegabyteString) {
  const fs::path dir = temp_dir("fuzz-huge-string");
  const std::string huge(10 << 20, 'x');
  const std::string scene =
      "simulation: { dt: 0.01, steps: 10 }\n"
      "particles:\n  - { position: [0, 0, 0], mass: 1 }\n";
  // As a file name it is a valid scene (validate writes nothing).
  write_file(dir / "path.yaml", scene + "output: { path: " + huge + " }\n");
  const auto ok = pdyn({"validate", (dir / "path.yaml").string(), "-q"});
  EXPECT_EQ(ok.status, 0) << ok.err.substr(0, 500);
}

}  // namespace
}  // namespace pdyn
