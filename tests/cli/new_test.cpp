// `pdyn new`: what it writes and what it refuses. Building the projects it
// writes is the CTest test sdk.new (tests/sdk/check_new.cmake).
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "pdyn/host/version.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) { return test::read_bytes(p); }

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), {}));
}

// docs/plugins.md names the files `pdyn new` writes; for every kind they
// are exactly the files it writes (NAME standing for the plugin's name).
TEST(New, TheGuideListsExactlyTheFilesItWrites) {
  const std::string guide = read(test::source_path("docs/plugins.md"));
  const auto from = guide.find("`pdyn new KIND NAME [DIR]` writes");
  ASSERT_NE(from, std::string::npos) << "docs/plugins.md no longer describes pdyn new's files";
  const std::string paragraph = guide.substr(from, guide.find("\n\n", from) - from);
  std::set<std::string> listed;
  const std::regex file("`([A-Za-z_]+\\.(txt|cpp|md|yaml))`");
  for (std::sregex_iterator m(paragraph.begin(), paragraph.end(), file), end; m != end; ++m) {
    listed.insert((*m)[1]);
  }
  const char* count[] = {"no", "one", "two", "three", "four", "five", "six", "seven", "eight"};
  ASSERT_LT(listed.size(), std::size(count));
  EXPECT_NE(paragraph.find(std::string("writes ") + count[listed.size()] + " files"),
            std::string::npos)
      << "the guide's count of files does not match its list: " << paragraph;
  const fs::path root = test::temp_dir("new-files");
  for (const std::string kind : {"force", "solver", "collider", "writer", "pair", "constraint"}) {
    SCOPED_TRACE(kind);
    const fs::path dir = root / kind;
    const auto r = test::pdyn({"new", kind, "demo_" + kind, dir.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    std::set<std::string> written;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      std::string name = fs::relative(e.path(), dir).string();
      if (const auto at = name.find("demo_" + kind); at != std::string::npos) {
        name.replace(at, kind.size() + 5, "NAME");
      }
      written.insert(name);
    }
    EXPECT_EQ(written, listed);
    // The README points at the guide for its kind: pairs.md for a pair law,
    // constraints.md for a constraint.
    const std::string readme = read(dir / "README.md");
    const std::string guide_page = kind == "pair"         ? "pairs.md"
                                   : kind == "constraint" ? "constraints.md"
                                                          : "plugins.md";
    EXPECT_NE(readme.find(guide_page), std::string::npos) << readme;
  }
}

TEST(New, WritesAProjectForEachKind) {
  const fs::path root = test::temp_dir("new-kinds");
  for (const std::string kind : {"force", "solver", "collider", "writer", "constraint"}) {
    const std::string name = "my_" + kind;
    const fs::path dir = root / name;
    const auto r = test::pdyn({"new", kind, name, dir.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(entries(dir), 5u);  // CMakeLists.txt, NAME.cpp, test_NAME.cpp, README.md, scene.yaml
    const std::string cmake = read(dir / "CMakeLists.txt");
    // The project asks for the release it was written against (MAJOR.MINOR).
    const std::string release(host::version());
    const std::string wanted = release.substr(0, release.rfind('.'));
    EXPECT_NE(cmake.find("find_package(pdyn " + wanted + " REQUIRED)"), std::string::npos) << cmake;
    EXPECT_NE(
        cmake.find("pdyn_add_plugin(" + name + " KIND " + kind + " SOURCES " + name + ".cpp)"),
        std::string::npos)
        << cmake;
    EXPECT_NE(cmake.find("${PDYN_EXECUTABLE} check " + name), std::string::npos) << cmake;
    const std::string source = read(dir / (name + ".cpp"));
    EXPECT_NE(source.find("d.name = \"" + name + "\";"), std::string::npos);
    EXPECT_NE(read(dir / "scene.yaml").find("type: " + name), std::string::npos);
    EXPECT_NE(read(dir / "README.md").find("pdyn new " + kind + " " + name), std::string::npos);
    // Every placeholder was replaced.
    for (const auto& e : fs::directory_iterator(dir)) {
      EXPECT_EQ(read(e.path()).find('@'), std::string::npos) << e.path();
    }
  }
  EXPECT_EQ(entries(root), 5u) << "no temporary folder left behind";
}

// A kind's own template replaces the common one of the same path: a
// constraint project's test_NAME.cpp is the constraint's (the conformance
// kit and a physics test), written once; a force's is the common one.
TEST(New, AKindsOwnTestFileReplacesTheCommonOne) {
  const fs::path root = test::temp_dir("new-override");
  ASSERT_EQ(test::pdyn({"new", "constraint", "bowl2", (root / "c").string()}).status, 0);
  ASSERT_EQ(test::pdyn({"new", "force", "tether2", (root / "f").string()}).status, 0);
  const std::string constraint_test = read(root / "c" / "test_bowl2.cpp");
  EXPECT_NE(constraint_test.find("TEST(bowl2, PassesTheConformanceKit)"), std::string::npos);
  EXPECT_NE(constraint_test.find("TEST(bowl2, ConstraintForceKeepsACircularOrbit)"),
            std::string::npos);
  // Issue 42 (6g): a test for any geometry, and the bowl's own marked for
  // replacing.
  EXPECT_NE(constraint_test.find("TEST(bowl2, ParticlesStayOnTheConstraintUnderGravity)"),
            std::string::npos);
  EXPECT_NE(constraint_test.find("// TODO(bowl2): this test is the bowl's exact solution"),
            std::string::npos);
  EXPECT_EQ(read(root / "f" / "test_tether2.cpp").find("Orbit"), std::string::npos);
  EXPECT_EQ(entries(root / "c"), 5u);
}

// Issue 42 (6g): the "next:" lines end with one naming the project's test
// file and what to do with it.
TEST(New, NextLinesNameTheTestFile) {
  const fs::path root = test::temp_dir("new-next");
  const auto c = test::pdyn({"new", "constraint", "helix", (root / "c").string()});
  ASSERT_EQ(c.status, 0) << c.err;
  const std::string constraint_line =
      "  " + (root / "c" / "test_helix.cpp").string() +
      ": your tests; keep the first three (any geometry), replace the bowl's orbit test with "
      "your geometry's exact case (its TODO says what to assert)\n";
  EXPECT_NE(c.out.find("  ctest --test-dir " + (root / "c").string() +
                       "/build      # pdyn check helix, the example scene and test_helix\n" +
                       constraint_line),
            std::string::npos)
      << c.out;
  EXPECT_EQ(c.out.substr(c.out.size() - constraint_line.size()), constraint_line) << c.out;
  const auto f = test::pdyn({"new", "force", "tether3", (root / "f").string()});
  ASSERT_EQ(f.status, 0) << f.err;
  const std::string force_line = "  " + (root / "f" / "test_tether3.cpp").string() +
                                 ": your tests; add your physics (exact solutions, conservation "
                                 "laws) beside the conformance kit's\n";
  EXPECT_EQ(f.out.substr(f.out.size() - force_line.size()), force_line) << f.out;
}

TEST(New, DefaultFolderIsTheNameAndAnEmptyFolderIsFine) {
  const fs::path root = test::temp_dir("new-default");
  const fs::path empty = root / "empty";
  fs::create_directory(empty);
  EXPECT_EQ(test::pdyn({"new", "solver", "heun2", empty.string()}).status, 0);
  EXPECT_TRUE(fs::exists(empty / "heun2.cpp"));
  const fs::path before = fs::current_path();
  fs::current_path(root);
  const auto r = test::pdyn({"new", "collider", "floor2"});
  fs::current_path(before);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(root / "floor2" / "floor2.cpp"));
}

struct Refusal {
  std::vector<std::string> args;  // after "new"; DIR is appended
  std::string message;
};

TEST(New, RefusesBadNamesKindsAndFoldersWithExit2) {
  const fs::path root = test::temp_dir("new-refusals");
  test::write_file(root / "full" / "keep.txt", "x");
  test::write_file(root / "a_file", "x");
  const std::vector<Refusal> cases = {
      {{"force", "Wind"}, "'Wind' is not a valid plugin name (expected [a-z0-9_]+"},
      {{"force", "my-wind"}, "'my-wind' is not a valid plugin name"},
      {{"force", ""}, "'' is not a valid plugin name"},
      {{"force", "test"}, "'test' is a target name that CMake reserves"},
      {{"force", "gravity"}, "a plugin named 'gravity' already exists"},
      {{"solver", "fine", (root / "full").string()}, "full exists and is not empty"},
      {{"solver", "fine", (root / "a_file").string()}, "a_file exists and is not a folder"},
      {{"spring", "fine"}, "kind"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> args = {"new"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    if (c.args.size() == 2) args.push_back((root / "target").string());
    const auto r = test::pdyn(args);
    EXPECT_EQ(r.status, 2) << c.message << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(root / "target"));
  EXPECT_EQ(entries(root / "full"), 1u);
  EXPECT_EQ(entries(root), 2u) << "nothing written by a refused command";
}

TEST(New, AnUnwritableParentLeavesNothingBehind) {
  const fs::path root = test::temp_dir("new-unwritable");
  test::write_file(root / "a_file", "x");
  const auto r = test::pdyn({"new", "force", "wind", (root / "a_file" / "wind").string()});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("pdyn: cannot create "), std::string::npos) << r.err;
  EXPECT_EQ(entries(root), 1u);
}

}  // namespace
}  // namespace pdyn
