// Where docs/scenes.md and the plugins' descriptions promise something the
// loader used to refuse: each promise, kept.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "pdyn/host/scene.hpp"
#include "pdyn/pair.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

std::string message(const std::string& yaml) {
  try {
    test::load_text(yaml);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

// The spring plugin describes `rest` as "one for all pairs or one per pair":
// a plain number is the one for all, the same as a one-element list.
TEST(DocAgreement, ASpringTakesOneRestLengthAsANumber) {
  const std::string head =
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1 }\n"
      "  - { position: [0.3, 0, 0], mass: 1 }\n"
      "  - { position: [0, 0.5, 0], mass: 1 }\n"
      "forces:\n";
  Scene scalar = test::load_text(head +
                                 "  - { type: spring, pairs: [[0, 1], [0, 2]], ks: 10, "
                                 "rest: 0.1 }\n");
  Scene list = test::load_text(head +
                               "  - { type: spring, pairs: [[0, 1], [0, 2]], ks: 10, "
                               "rest: [0.1] }\n");
  const Matrix3X f = test::ForcesOf(*scalar.system, 0);
  EXPECT_EQ(f, test::ForcesOf(*list.system, 0));
  EXPECT_NEAR(f(0, 1), -10 * (0.3 - 0.1), 1e-12);  // stretched by 0.2 m
  EXPECT_NEAR(f(1, 2), -10 * (0.5 - 0.1), 1e-12);
  // Not a number is still refused, with what was given.
  EXPECT_NE(message(head + "  - { type: spring, pairs: [[0, 1]], rest: abc }\n")
                .find("forces[0].rest: 'abc' is not a number (expected a number >= 0 in m)"),
            std::string::npos)
      << message(head + "  - { type: spring, pairs: [[0, 1]], rest: abc }\n");
}

// `fixed` takes 0 and 1 in a CSV side file; the YAML particle takes them too.
TEST(DocAgreement, FixedTakesZeroAndOneAsInCsvFiles) {
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - { position: [0, 0, 0], mass: 1, fixed: 1 }\n"
      "  - { position: [1, 0, 0], mass: 1, fixed: 0 }\n"
      "  - { position: [2, 0, 0], mass: 1, fixed: true }\n");
  const auto& fixed = scene.system->fixed();
  ASSERT_EQ(fixed.size(), 3u);
  EXPECT_EQ(fixed[0], 1);
  EXPECT_EQ(fixed[1], 0);
  EXPECT_EQ(fixed[2], 1);
  EXPECT_NE(message("simulation: { dt: 0.01, steps: 1 }\n"
                    "particles:\n"
                    "  - { position: [0, 0, 0], mass: 1, fixed: 2 }\n")
                .find("particles[0].fixed: '2' is not true or false (expected true, false, 1 or "
                      "0)"),
            std::string::npos);
}

// docs/scenes.md lists the sources of potential energy and says which
// plugins read groups: checked against what the plugins do.
TEST(DocAgreement, ScenesMdNamesThePluginsThatReportPotentialEnergyAndReadGroups) {
  std::ifstream in(test::source_path("docs/scenes.md"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  EXPECT_EQ(doc.find("No shipped plugin reads groups yet"), std::string::npos);
  // One particle, one of each force with its potential: each reports one.
  Scene scene = test::load_text(
      "simulation: { dt: 0.01, steps: 1 }\n"
      "particles:\n"
      "  - chain: { from: [0, 0, 1], to: [1, 0, 1], n: 3, mass: 1, bend: { k: 1 } }\n"
      "  - ring: { center: [0, 0, 3], radius: 0.5, n: 4, mass: 1, area: { k: 1 } }\n"
      "  - { position: [9, 9, 9], mass: 1, radius: 0.1 }\n"
      "forces:\n"
      "  - { type: gravity }\n"
      "  - { type: drag, k: 0.1 }\n"
      "  - { type: langevin, kT: 1, damp: 1 }\n"
      "  - { type: field, force: ['-x', '0', '0'], potential: 'x^2/2' }\n"
      "  - { type: anchor, ids: [0], points: [[0, 0, 0]] }\n"
      "  - { type: attractor, center: [5, 5, 5] }\n"
      "  - { type: lennard_jones }\n"
      "  - { type: soft_contact }\n"
      "  - { type: nbody }\n"
      "  - { type: dihedral, quads: [[0, 1, 2, 3]] }\n"
      "  - { type: dihedral_opls, quads: [[0, 1, 2, 3]], k1: 1, k2: 0, k3: 0, k4: 0 }\n"
      "  - { type: dihedral_harmonic, quads: [[0, 1, 2, 3]], k: 1, d: 1, n: 2 }\n"
      "  - { type: angle_cosine_squared, triples: [[0, 1, 2]], k: 1, theta0: 2 }\n"
      "  - { type: improper_harmonic, quads: [[0, 1, 2, 3]], k: 1, chi0: 0.5 }\n"
      "  - { type: fene, pairs: [[0, 1]], k: 30, r0: 1.5, epsilon: 1, sigma: 1 }\n");
  const auto start = doc.find("`potential` is the sum of the potential");
  ASSERT_NE(start, std::string::npos);
  const std::string sentence = doc.substr(start, doc.find("\n\n", start) - start);
  // The sentence names those that report one before its ';', and those that
  // do not ("drag does not") after it.
  const std::string reporters = sentence.substr(0, sentence.find(';'));
  std::set<std::string> in_scene;
  for (const auto& f : scene.system->force_objects()) {
    const std::string type = f.label.substr(0, f.label.find(' '));
    in_scene.insert(type);
    const bool reports = f.force->potential_energy(scene.system->view()).has_value();
    const bool named = sentence.find(type) != std::string::npos;
    EXPECT_TRUE(named) << type << " is not named in: " << sentence;
    EXPECT_EQ(reports, reporters.find(type) != std::string::npos)
        << type << (reports ? " reports a potential energy" : " reports none")
        << ", which the sentence does not say: " << sentence;
  }
  // Every shipped force is in the scene above, so a new one must be added
  // there and named in the sentence.
  for (const auto& r : test::shipped_plugins().plugins()) {
    if (r.descriptor->kind != PluginKind::Force) continue;
    EXPECT_TRUE(in_scene.count(r.descriptor->name))
        << "the shipped force " << r.descriptor->name << " is not in this test's scene";
  }
  // "every pair force written on PairForce": any law, central or not, with
  // or without types, gives a potential energy.
  struct Central {
    PairTerm operator()(double, std::int32_t, std::int32_t) const { return {0.5, 0.0}; }
  };
  struct General {
    PairVector operator()(const ParticleView&, const PairPoint&) const { return {}; }
  };
  const std::string flat = std::regex_replace(reporters, std::regex("\\s+"), " ");
  EXPECT_NE(flat.find("every pair force written on `PairForce`"), std::string::npos) << sentence;
  const ParticleView view = scene.system->view();
  const std::optional<double> central =
      PairForce<Central>(Central{}, 1.0, 0.1).potential_energy(view);
  ASSERT_TRUE(central.has_value());
  EXPECT_TRUE(PairForce<General>(General{}, 1.0, 0.1).potential_energy(view).has_value());
  // 0.5 J for each pair of the scene's particles closer than 1 m.
  const auto& x = view.x;
  int close = 0;
  for (Index i = 0; i < x.cols(); ++i) {
    for (Index j = i + 1; j < x.cols(); ++j) close += (x.col(i) - x.col(j)).norm() < 1.0;
  }
  EXPECT_EQ(*central, 0.5 * close);
}

// README's "Shipped plugins" table lists exactly the shipped plugins, each
// under its kind, and links each to its own folder.
TEST(DocAgreement, ReadmeListsExactlyTheShippedPlugins) {
  const std::string readme = test::read_bytes(test::source_path("README.md"));
  const auto from = readme.find("## Shipped plugins");
  ASSERT_NE(from, std::string::npos);
  const std::string section = readme.substr(from, readme.find("\n## ", from + 1) - from);
  std::set<std::string> listed;
  const std::regex row(R"(\| (\w+) \| \[(\w+)\]\(plugins/(\w+)s/(\w+)/\) \|)");
  for (std::sregex_iterator m(section.begin(), section.end(), row), end; m != end; ++m) {
    EXPECT_EQ((*m)[1], (*m)[3]) << "the link of " << (*m)[2] << " is not under its kind's folder";
    EXPECT_EQ((*m)[2], (*m)[4]) << "the link of " << (*m)[2] << " is not its own folder";
    listed.insert(std::string((*m)[1]) + " " + std::string((*m)[2]));
  }
  std::set<std::string> shipped;
  for (const auto& r : test::shipped_plugins().plugins()) {
    shipped.insert(std::string(kind_name(r.descriptor->kind)) + " " + r.descriptor->name);
  }
  EXPECT_EQ(listed, shipped);
}

}  // namespace
}  // namespace pdyn
