// The field plugin's expression language as plugins/forces/field/README.md
// documents it: every example of its tables is evaluated through the plugin
// and must give the documented value (or be refused with the documented
// message), and the functions table must list exactly the functions the
// parser knows. So the README cannot drift from what muParser accepts.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "pdyn/host/scene.hpp"
#include "plugins/forces/force_support.hpp"

namespace pdyn {
namespace {

struct Row {
  int line = 0;
  std::string expr, value, note;
};

// The cells of a Markdown table row, with `\|` unescaped.
std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  for (std::size_t i = 1; i < line.size(); ++i) {
    if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
      cell += '|';
      ++i;
    } else if (line[i] == '|') {
      const auto b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
      out.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
      cell.clear();
    } else {
      cell += line[i];
    }
  }
  return out;
}

// The rows `| `EXPR` | VALUE | ... |` of the README's "Expression language" section.
std::vector<Row> documented_rows() {
  std::ifstream in(test::source_path("plugins/forces/field/README.md"));
  std::vector<Row> rows;
  bool inside = false, examples = false;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (line.rfind("## ", 0) == 0) inside = line == "## Expression language";
    // Only the tables of examples: their header is "| expression | value | ...".
    if (line.empty() || line[0] != '|') examples = false;
    if (line.rfind("| expression | value |", 0) == 0) examples = true;
    if (!inside || !examples || line.rfind("| `", 0) != 0) continue;
    const auto c = cells(line);
    if (c.size() < 3 || c[0].size() < 2 || c[0].back() != '`') continue;
    rows.push_back({number, c[0].substr(1, c[0].size() - 2), c[1], c[2]});
  }
  return rows;
}

// Particle 0 at x = 0.5, y = -2, z = 3, v = (1, 0, -1), m = 2, t = 0.
std::string scene_with(const std::string& expr) {
  std::string quoted;
  for (char ch : expr) quoted += ch == '"' ? std::string("\\\"") : std::string(1, ch);
  return "simulation: { dt: 0.01, steps: 1 }\n"
         "particles:\n"
         "  - { position: [0.5, -2, 3], velocity: [1, 0, -1], mass: 2 }\n"
         "forces:\n"
         "  - { type: field, force: [\"" +
         quoted + "\", \"0\", \"0\"] }\n";
}

std::string expression_refusal(const std::string& expr) {
  try {
    test::load_text(scene_with(expr));
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(FieldExpressionLanguage, EveryDocumentedExampleGivesItsValue) {
  const auto rows = documented_rows();
  ASSERT_GE(rows.size(), 50u) << "the README's tables were not found";
  for (const auto& r : rows) {
    SCOPED_TRACE("README.md:" + std::to_string(r.line) + ": " + r.expr);
    if (r.value == "refused") {
      const std::string message = expression_refusal(r.expr);
      EXPECT_NE(message.find(r.note), std::string::npos) << message;
      continue;
    }
    double expected = 0;
    ASSERT_NO_THROW(expected = std::stod(r.value)) << "value '" << r.value << "'";
    Scene scene;
    ASSERT_NO_THROW(scene = test::load_text(scene_with(r.expr))) << expression_refusal(r.expr);
    const double got = test::ForcesOf(*scene.system, 0)(0, 0);
    EXPECT_NEAR(got, expected, 1e-15 * std::max(1.0, std::abs(expected)))
        << "documented " << r.value;
  }
}

TEST(FieldExpressionLanguage, EveryFunctionOfTheParserIsDocumented) {
  // The plugin lists the parser's functions when it refuses an unknown one.
  const std::string message = expression_refusal("zzzzzz(x)");
  const std::string lead = "expected one of the functions ";
  const auto at = message.find(lead);
  ASSERT_NE(at, std::string::npos) << message;
  std::set<std::string> known;
  std::istringstream list(message.substr(at + lead.size(), message.rfind(')') - at - lead.size()));
  for (std::string name; std::getline(list >> std::ws, name, ',');) known.insert(name);
  ASSERT_GE(known.size(), 20u) << message;
  std::set<std::string> documented;
  for (const auto& r : documented_rows()) {
    // A call: a name, then '('.
    const auto paren = r.expr.find('(');
    if (r.value == "refused" || paren == std::string::npos || paren == 0) continue;
    const std::string name = r.expr.substr(0, paren);
    if (name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos) {
      continue;
    }
    documented.insert(r.expr.substr(0, paren));
  }
  EXPECT_EQ(documented, known);
  // The constants, likewise: both named, and nothing else called a constant.
  for (const char* c : {"_pi", "_e"}) {
    EXPECT_EQ(expression_refusal(c), "(accepted)") << c;
  }
}

}  // namespace
}  // namespace pdyn
