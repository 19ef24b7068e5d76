// The `output:` list of writers as the scene loader reads it (docs/output.md):
// each writer with its own path, every and fields; the mapping form as one
// csv and one energy writer; and every bad entry a located error before the
// simulation starts: an unknown writer, a path that is a folder or cannot
// be written, two writers to one file, an unknown or unsupported field,
// `every` below 1, two checkpoints.
#include <gtest/gtest.h>
#include <unistd.h>

#include "pdyn/host/scene.hpp"
#include "pdyn/host/scene_specs.hpp"
#include "support/test_support.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using pdyn::test::shipped_plugins;

const char* kOutputHead =
    "simulation: { dt: 0.01, steps: 10 }\n"
    "particles:\n"
    "  - { position: [0, 0, 1], mass: 1 }\n"
    "  - { position: [1, 0, 1], mass: 1 }\n";

Scene load_output(const std::string& output) {
  return load_scene_text(std::string(kOutputHead) + output, "s.yaml", shipped_plugins());
}

// The diagnostics of a refused scene, one per line.
std::string refused(const std::string& output) {
  try {
    load_output(output);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(OutputList, EachWriterHasItsPathEveryAndFields) {
  const Scene s = load_output(
      "output:\n"
      "  - { type: csv, path: out/run.csv, every: 10 }\n"
      "  - { type: vtk, path: out/run.pvd, every: 50, fields: [velocity, mass, fixed, force] }\n"
      "  - { type: h5md, path: out/run.h5, every: 10, compression: 6 }\n");
  const auto& w = s.output.writers;
  ASSERT_EQ(w.size(), 3u);
  EXPECT_EQ(w[0].record.descriptor->name, "csv");
  EXPECT_EQ(w[0].path, "out/run.csv");
  EXPECT_EQ(w[0].every, 10);
  EXPECT_FALSE(w[0].params.boolean("unwrapped"));
  EXPECT_EQ(w[1].label, "vtk (s.yaml:7:5)");
  EXPECT_EQ(w[1].every, 50);
  EXPECT_EQ(w[1].fields, (std::vector<std::string>{"velocity", "mass", "fixed", "force"}));
  EXPECT_EQ(w[2].fields,
            (std::vector<std::string>{"id", "velocity", "mass", "fixed", "radius", "type"}));
  EXPECT_EQ(w[2].params.integer("compression"), 6);
  EXPECT_EQ(w[2].params.values().size(), 1u);  // path, every and fields are the host's
  EXPECT_EQ(s.output.checkpoint_beside, "out/run.csv");
}

TEST(OutputList, TheMappingFormIsACsvAndAnEnergyWriter) {
  const Scene s =
      load_output("output: { path: f.csv, every: 0, energy: e.csv, unwrapped: true }\n");
  const auto& w = s.output.writers;
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].record.descriptor->name, "csv");
  EXPECT_EQ(w[0].label, "csv (s.yaml:5:17)");
  EXPECT_EQ(w[0].every, 0);  // first and final frames only, as before
  EXPECT_TRUE(w[0].params.boolean("unwrapped"));
  EXPECT_EQ(w[1].record.descriptor->name, "energy");
  EXPECT_EQ(w[1].path, "e.csv");
  EXPECT_EQ(w[1].every, 0);
  EXPECT_EQ(s.output.checkpoint_beside, "f.csv");
}

TEST(OutputList, CheckpointAtTheTopLevel) {
  const Scene s = load_output(
      "output: [ { type: csv, path: a.csv } ]\n"
      "checkpoint: { path: c/run.ckpt, every: 5 }\n");
  EXPECT_EQ(s.output.checkpoint, "c/run.ckpt");
  EXPECT_EQ(s.output.checkpoint_every, 5);
  EXPECT_EQ(refused("output: { path: a.csv, checkpoint: { path: x.ckpt } }\n"
                    "checkpoint: { path: y.ckpt }\n"),
            "s.yaml:6:13: checkpoint: the checkpoint is also given as output.checkpoint.path "
            "(expected one of them)");
}

TEST(OutputList, UnknownWriter) {
  EXPECT_EQ(refused("output:\n  - { type: vtkk, path: out/a.pvd }\n"),
            "s.yaml:6:13: output[0].type: unknown writer type 'vtkk' (did you mean 'vtk'? "
            "expected one of: csv, energy, h5md, vtk)");
  EXPECT_EQ(refused("output:\n  - { type: spring, path: out/a.pvd }\n"),
            "s.yaml:6:13: output[0].type: 'spring' is a force plugin, not a writer (expected one "
            "of: csv, energy, h5md, vtk)");
}

TEST(OutputList, PathIsAFolder) {
  const fs::path dir = pdyn::test::temp_dir("output-list-folder");
  EXPECT_EQ(refused("output:\n  - { type: csv, path: " + dir.string() + " }\n"),
            "s.yaml:6:24: output[0].path: '" + dir.string() +
                "' is a folder, not a file (expected a file name, e.g. out/run.csv)");
  EXPECT_EQ(refused("output:\n  - { type: vtk, path: out/ }\n"),
            "s.yaml:6:24: output[0].path: 'out/' is a folder, not a file (expected a file name, "
            "e.g. out/run.csv)");
}

TEST(OutputList, PathCannotBeWritten) {
  const fs::path dir = pdyn::test::temp_dir("output-list-readonly");
  fs::permissions(dir, fs::perms::owner_read | fs::perms::owner_exec);
  if (::access(dir.c_str(), W_OK) == 0) {
    fs::permissions(dir, fs::perms::owner_all);
    GTEST_SKIP() << "this user (root) may write in a read-only folder";
  }
  const std::string got =
      refused("output:\n  - { type: csv, path: " + (dir / "sub/a.csv").string() + " }\n");
  fs::permissions(dir, fs::perms::owner_all);
  EXPECT_EQ(got, "s.yaml:6:24: output[0].path: cannot write '" + (dir / "sub/a.csv").string() +
                     "': the folder '" + dir.string() +
                     "' is not writable (Permission denied) (expected a folder this user can "
                     "write)");
}

TEST(OutputList, TwoWritersToOneFile) {
  EXPECT_EQ(refused("output:\n"
                    "  - { type: csv, path: out/a.csv }\n"
                    "  - { type: energy, path: out/./a.csv }\n"),
            "s.yaml:7:27: output[1].path: 'out/./a.csv' is the same file as output[0].path (at "
            "s.yaml:6:24) (expected a different file for each output)");
}

TEST(OutputList, UnknownAndUnsupportedFields) {
  EXPECT_EQ(refused("output:\n  - { type: vtk, path: a.pvd, fields: [velocity, colour] }\n"),
            "s.yaml:6:50: output[0].fields[1]: unknown field 'colour' for the 'vtk' writer "
            "(expected one of: id, velocity, mass, fixed, radius, type, force, image)");
  EXPECT_EQ(refused("output:\n  - { type: csv, path: a.csv, fields: [force] }\n"),
            "s.yaml:6:40: output[0].fields[0]: unsupported field 'force' for the 'csv' writer "
            "(expected no fields: its columns are fixed)");
}

TEST(OutputList, EveryBelowOne) {
  EXPECT_EQ(refused("output:\n  - { type: h5md, path: a.h5, every: 0 }\n"),
            "s.yaml:6:38: output[0].every: 0 is out of range (expected a whole number >= 1)");
  EXPECT_EQ(refused("output:\n  - { type: h5md, path: a.h5, compression: 10 }\n"),
            "s.yaml:6:44: output[0].compression: 10 is out of range (expected a whole number in "
            "[0, 9])");
}

TEST(OutputList, WriterEntryKeysAreTheHosts) {
  std::vector<std::string> names;
  for (const auto& s : writer_entry_keys()) names.push_back(s.name);
  EXPECT_EQ(names, (std::vector<std::string>{"path", "every", "fields"}));
}

}  // namespace
}  // namespace pdyn
