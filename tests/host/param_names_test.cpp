// Parameter names (issue #16): `G` is a name physicists use and is accepted;
// a name that breaks the rule is refused with the rule spelled out, not just
// "is not allowed". Fixtures in PDYN_FIXTURE_DIR/names (tests/fixtures/param_names.cpp).
#include <gtest/gtest.h>

#include "support/test_support.hpp"

namespace pdyn {
namespace {

using namespace pdyn::test;

TEST(ParamNames, TheRule) {
  for (const char* ok : {"G", "k", "k_spring", "_private", "Kx2", "rest"}) {
    EXPECT_TRUE(is_valid_param_name(ok)) << ok;
  }
  for (const char* bad : {"", "type", "2k", "k-x", "k x", "k.x", "é"}) {
    EXPECT_FALSE(is_valid_param_name(bad)) << bad;
  }
}

TEST(ParamNames, UpperCaseIsAcceptedAndReadFromTheScene) {
  PluginRegistry r;
  r.discover({std::string(PDYN_FIXTURE_DIR) + "/names", PDYN_PLUGIN_DIR});
  ASSERT_NE(r.find(PluginKind::Force, "upper_case"), nullptr);
  const Scene s = load_scene_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n  - { position: [0, 0, 0], mass: 1 }\n"
      "forces:\n  - { type: upper_case, G: 1.5 }\n",
      "g.yaml", r);
  ASSERT_EQ(s.uses.size(), 1u);
  EXPECT_EQ(s.uses[0].params.real("G"), 1.5);
}

TEST(ParamNames, ABadNameIsRefusedWithTheRule) {
  PluginRegistry r;
  r.discover({std::string(PDYN_FIXTURE_DIR) + "/names"});
  const PluginFault* fault = nullptr;
  for (const auto& f : r.faults()) {
    if (f.plugin == "bad_param_name") fault = &f;
  }
  ASSERT_NE(fault, nullptr);
  EXPECT_EQ(fault->message,
            "parameter name 'k-x' is not allowed (expected a letter or '_', then letters, "
            "digits or '_', e.g. G or k_spring; not 'type', which names the plugin)");
}

}  // namespace
}  // namespace pdyn
