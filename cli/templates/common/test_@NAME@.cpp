// @NAME@'s own tests (GoogleTest): the plugin's objects are linked into this
// program, so its descriptor is at hand without loading a library. The first
// test runs every check of the conformance kit; add tests of your physics
// beside it (analytic solutions, conservation laws, known values).
#include <gtest/gtest.h>

#include <pdyn/conformance.hpp>
#include <pdyn/plugin.hpp>

TEST(@NAME@, PassesTheConformanceKit) {
  const auto results = pdyn::conformance::run_checks(*pdyn_plugin_descriptor(), {.seed = 1});
  ASSERT_FALSE(results.empty());
  for (const auto& r : results) {
    EXPECT_NE(r.verdict, pdyn::conformance::Verdict::Fail) << r.name << ": " << r.detail;
  }
}

TEST(@NAME@, DescriptorNamesThisPlugin) {
  EXPECT_EQ(pdyn_plugin_descriptor()->name, "@NAME@");
}
