// field: a force field given by three expressions, f = (fx, fy, fz)(x, y, z,
// vx, vy, vz, t, m), evaluated for each selected particle, with named
// constants and an optional potential U(x, y, z, t, m) so that the energy is
// reported (and `pdyn check` verifies f = -grad U).
//
// Expressions are compiled once, by muParser (Berg, muparser.beltoforion.de),
// into its bytecode; each derivative evaluation then only binds the
// particle's variables and runs the bytecode. muParser's bulk mode is not
// used: Debian builds it with OpenMP, so it would start worker threads
// inside a force (the kernel's forces run on the caller's thread), and its
// per-variable arrays would need the 3 x N state copied into 8 arrays on
// every evaluation; the per-particle loop is fast enough for the gallery's
// thousand-particle scenes.
#include <dlfcn.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <muParser.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <memory>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>
#include <pdyn/text.hpp>
#include <pdyn/thermo.hpp>
#include <string>
#include <vector>

namespace {

using pdyn::Index;
using pdyn::ParamError;

// The variables an expression may use, in the order of Field::vars_.
constexpr std::array<const char*, 8> kVariables = {"x", "y", "z", "vx", "vy", "vz", "t", "m"};
constexpr const char* kVariableList = "x, y, z, vx, vy, vz, t, m";

bool is_name(const std::string& s) {
  return !s.empty() && !std::isdigit(static_cast<unsigned char>(s[0])) &&
         std::all_of(s.begin(), s.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
         });
}

// "did you mean 'sin' or 'sinh'? ": the known names nearest to `word`, if
// close enough to be a typo (one edit per three letters, at least two, and
// fewer than the word's letters).
std::string suggestion(const std::string& word, const std::vector<std::string>& known) {
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  std::size_t best = limit + 1;
  std::vector<std::string> nearest;
  for (const auto& k : known) {
    const std::size_t d = pdyn::edit_distance(word, k);
    if (d < best) {
      best = d;
      nearest.clear();
    }
    if (d == best) nearest.push_back(k);
  }
  // A name as short as its distance (q for x) is no typo of it.
  if (nearest.empty() || best >= word.size()) return "";
  std::string s = "did you mean ";
  for (std::size_t i = 0; i < nearest.size(); ++i) {
    s += fmt::format("{}'{}'", i == 0 ? "" : i + 1 == nearest.size() ? " or " : ", ", nearest[i]);
  }
  return s + "? ";
}

// The functions `parser` knows, sorted: muParser's built-ins.
std::vector<std::string> function_names(const mu::Parser& parser) {
  std::vector<std::string> names;
  for (const auto& kv : parser.GetFunDef()) names.push_back(kv.first);
  std::sort(names.begin(), names.end());
  return names;
}

// What explain() reports: what muParser found, a "did you mean" hint
// (empty, or ending in "? ") and what the expression may contain.
struct Diagnosis {
  std::string what, hint, expected;
};

// muParser's text for an error explain() has no words of its own for, without
// its "... at position N." and " found" (the position follows).
std::string muparser_message(const mu::ParserError& e) {
  std::string what = e.GetMsg();
  if (const auto at = what.find(" at position"); at != std::string::npos) what.resize(at);
  if (const auto found = what.rfind(" found");
      found != std::string::npos && found + 6 == what.size()) {
    what.resize(found);
  }
  if (!what.empty()) what[0] = static_cast<char>(std::tolower(what[0]));
  return what;
}

// What muParser found, for the errors that name a token it did not expect
// where it was (every error but an unknown token and an unexpected operator).
std::string unexpected(const mu::ParserError& e) {
  const std::string& tok = e.GetToken();
  switch (e.GetCode()) {
    case mu::ecUNEXPECTED_EOF:
      return "unexpected end of the expression";
    case mu::ecUNEXPECTED_ARG_SEP:
      return "unexpected ','";
    case mu::ecUNEXPECTED_PARENS:
      return fmt::format("unexpected parenthesis '{}'", tok);
    case mu::ecMISSING_PARENS:
      return "missing parenthesis ')'";
    case mu::ecUNEXPECTED_VAL:
      return fmt::format("unexpected value '{}'", tok);
    case mu::ecUNEXPECTED_VAR:
      return fmt::format("unexpected variable '{}'", tok);
    case mu::ecUNEXPECTED_FUN:
      return fmt::format("unexpected function '{}'", tok);
    case mu::ecTOO_MANY_PARAMS:
      return fmt::format("too many arguments to '{}'", tok);
    case mu::ecTOO_FEW_PARAMS:
      return fmt::format("too few arguments to '{}'", tok);
    default:
      return muparser_message(e);
  }
}

// A token muParser could not read (ecUNASSIGNABLE_TOKEN): an unknown function
// or variable, with the nearest known names, or a stray character. `names`
// lists the variables and constants.
void explain_unknown(const mu::ParserError& e, const std::string& expr, const std::string& names,
                     const mu::Parser& parser, const pdyn::NamedReals& user_constants,
                     Diagnosis& d) {
  const std::string& tok = e.GetToken();
  if (!is_name(tok)) {
    // muParser's token is the rest of the expression ("% 2 "): name its
    // first character, where the position points.
    d.what = fmt::format("unexpected '{}'", tok.empty() ? tok : tok.substr(0, 1));
    return;
  }
  // muParser reports an unknown function as an unknown token too: a name
  // followed by '(' was meant as a function.
  const auto after = e.GetPos() < 0 ? std::string::npos
                                    : expr.find_first_not_of(
                                          " \t", static_cast<std::size_t>(e.GetPos()) + tok.size());
  if (after != std::string::npos && expr[after] == '(') {
    const auto functions = function_names(parser);
    d.what = fmt::format("unknown function '{}'", tok);
    d.hint = suggestion(tok, functions);
    d.expected = fmt::format("one of the functions {}", fmt::join(functions, ", "));
    return;
  }
  d.what = fmt::format("unknown variable '{}'", tok);
  // `pi` for `_pi`, a typo in a variable or constant.
  std::vector<std::string> known(kVariables.begin(), kVariables.end());
  for (const auto& kv : parser.GetConst()) known.push_back(kv.first);
  for (const auto& kv : user_constants) known.push_back(kv.first);
  d.hint = suggestion(tok, known);
  d.expected = "one of " + names;
}

// "unexpected operator '*' at position 3 in "-k**y" (expected ...)": what
// muParser found, where (0-based character offset, as muParser counts), and
// what the expression may contain.
std::string explain(const mu::ParserError& e, const std::string& expr, const std::string& constants,
                    const mu::Parser& parser, const pdyn::NamedReals& user_constants) {
  const std::string& tok = e.GetToken();
  const std::string names =
      fmt::format("the variables {}{}", kVariableList,
                  constants.empty() ? "" : fmt::format(" or the constants {}", constants));
  Diagnosis d{"", "",
              fmt::format("an expression in {} and functions such as sin, "
                          "exp, sqrt",
                          names)};
  switch (e.GetCode()) {
    case mu::ecUNEXPECTED_OPERATOR:
      d.what = fmt::format("unexpected operator '{}'", tok);
      // Python's and Fortran's power operator: muParser's is '^'.
      if (tok == "*" && e.GetPos() > 0 && expr[static_cast<std::size_t>(e.GetPos()) - 1] == '*') {
        d.expected += "; a power is written x^2, not x**2";
      }
      break;
    case mu::ecUNASSIGNABLE_TOKEN:
      explain_unknown(e, expr, names, parser, user_constants, d);
      break;
    default:
      d.what = unexpected(e);
  }
  if (expr.find_first_not_of(" \t") == std::string::npos) {
    return fmt::format("the expression is empty (expected {})", d.expected);
  }
  if (e.GetPos() < 0) {
    return fmt::format("{} in \"{}\" ({}expected {})", d.what, expr, d.hint, d.expected);
  }
  return fmt::format("{} at position {} in \"{}\" ({}expected {})", d.what, e.GetPos(), expr,
                     d.hint, d.expected);
}

class Field final : public pdyn::Force, public pdyn::VirialSource {
 public:
  /// From outside the system: no virial (pdyn/thermo.hpp), as LAMMPS's fixes.
  double virial(const pdyn::ParticleView&) const override { return 0.0; }

  Field(const Field&) = delete;
  Field& operator=(const Field&) = delete;

  // Throws ParamError naming the parameter (and component) that is wrong.
  Field(const std::vector<std::string>& force, const std::string* potential,
        const pdyn::NamedReals& constants, pdyn::Selection selection)
      : selection_(std::move(selection)) {
    std::string constant_names;
    for (const auto& [name, value] : constants) {
      for (const char* v : kVariables) {
        if (name == v) {
          throw ParamError("constants",
                           fmt::format("constant '{}' is named like a variable (expected names "
                                       "other than {})",
                                       name, kVariableList));
        }
      }
      constant_names += (constant_names.empty() ? "" : ", ") + name;
    }
    auto compile = [&](mu::Parser& parser, const std::string& expr, const char* param,
                       long element) {
      try {
        for (std::size_t k = 0; k < kVariables.size(); ++k) {
          parser.DefineVar(kVariables[k], &vars_[k]);
        }
        for (const auto& [name, value] : constants) parser.DefineConst(name, value);
      } catch (const mu::ParserError& e) {
        // e.g. a constant named like a built-in function or constant (_pi).
        throw ParamError("constants", fmt::format("{} (expected names of your own, other than "
                                                  "muParser's functions and constants)",
                                                  e.GetMsg()));
      }
      // muParser's '=' assigns to a variable, which would change x (say) for
      // the components evaluated after this one: refused, '==' compares.
      for (std::size_t k = 0; k < expr.size(); ++k) {
        if (expr[k] != '=') continue;
        const char before = k > 0 ? expr[k - 1] : ' ';
        const char after = k + 1 < expr.size() ? expr[k + 1] : ' ';
        if (after == '=') {
          ++k;  // '=='
          continue;
        }
        if (before == '<' || before == '>' || before == '!') continue;
        throw ParamError(param,
                         fmt::format("'=' at position {} in \"{}\" would assign to a variable "
                                     "(expected '==' to compare)",
                                     k, expr),
                         element);
      }
      try {
        parser.SetExpr(expr);
        parser.Eval();  // parses and compiles now, so errors are found at load time
      } catch (const mu::ParserError& e) {
        throw ParamError(param, explain(e, expr, constant_names, parser, constants), element);
      }
      // Which variables it reads, for dependence(): a field of x, y, z and m
      // only lets velocity Verlet reuse its forces.
      for (const auto& [name, address] : parser.GetUsedVar()) {
        (void)address;
        if (name == "vx" || name == "vy" || name == "vz") reads_velocity_ = true;
        if (name == "t") reads_time_ = true;
      }
      if (parser.GetNumResults() != 1) {
        throw ParamError(param,
                         fmt::format("\"{}\" gives {} values (expected one number, without ',')",
                                     expr, parser.GetNumResults()),
                         element);
      }
    };
    if (force.size() != 3) {
      throw ParamError("force", fmt::format("has {} expression{} (expected 3: [fx, fy, fz], in N)",
                                            force.size(), force.size() == 1 ? "" : "s"));
    }
    for (int c = 0; c < 3; ++c) compile(component_[c], force[c], "force", c);
    if (potential) {
      potential_ = std::make_unique<mu::Parser>();
      compile(*potential_, *potential, "potential", -1);
    }
  }

  void add_forces(const pdyn::ParticleView& p, Eigen::Ref<pdyn::Matrix3X> f) override {
    vars_[6] = p.t;
    auto one = [&](Index i) {
      bind(p, i);
      for (int c = 0; c < 3; ++c) f(c, i) += component_[c].Eval();
    };
    if (selection_.all()) {
      for (Index i = 0; i < p.size(); ++i) one(i);
    } else {
      for (const Index i : selection_.ids()) one(i);
    }
  }

  pdyn::StateDependence dependence() const override { return {reads_velocity_, reads_time_}; }

  std::optional<double> potential_energy(const pdyn::ParticleView& p) const override {
    if (!potential_) return std::nullopt;
    vars_[6] = p.t;
    double u = 0.0;
    auto one = [&](Index i) {
      bind(p, i);
      u += potential_->Eval();
    };
    if (selection_.all()) {
      for (Index i = 0; i < p.size(); ++i) one(i);
    } else {
      for (const Index i : selection_.ids()) one(i);
    }
    return u;
  }

 private:
  void bind(const pdyn::ParticleView& p, Index i) const {
    for (int c = 0; c < 3; ++c) {
      vars_[c] = p.x(c, i);
      vars_[3 + c] = p.v(c, i);
    }
    vars_[7] = p.mass(i);
  }

  // The parsers hold the addresses of these: x, y, z, vx, vy, vz, t, m.
  // Mutable because potential_energy() is const but must bind them.
  mutable std::array<double, 8> vars_{};
  std::array<mu::Parser, 3> component_;
  std::unique_ptr<mu::Parser> potential_;
  bool reads_velocity_ = false, reads_time_ = false;  // some expression uses vx, vy, vz / t
  pdyn::Selection selection_;
};

std::unique_ptr<pdyn::Force> create(const pdyn::Params& p, const pdyn::SceneContext& ctx) {
  pdyn::Selection selection = pdyn::Selection::from_params(p, ctx);
  const std::string* potential = p.has("potential") ? &p.string("potential") : nullptr;
  return std::make_unique<Field>(p.strings("force"), potential, p.named_reals("constants"),
                                 std::move(selection));
}

// muParser, as Debian builds it, brings in the OpenMP runtime, whose static
// state keeps memory allocated while it is loaded. Unloading it together
// with this plugin (when the last object and registry let go) would unmap
// the only pointers to that memory, which LeakSanitizer then reports as
// leaked at exit. So this library, once loaded, stays resident: it marks
// itself RTLD_NODELETE (RTLD_NOLOAD: it is already loaded, nothing else is).
void keep_resident() {
  static const char self = 0;
  Dl_info info;
  if (dladdr(&self, &info) != 0 && info.dli_fname != nullptr) {
    (void)dlopen(info.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
  }
}

pdyn::PluginDescriptor describe() {
  keep_resident();
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "field";
  d.version = "1.0.0";
  d.description =
      "force field from expressions: f = [fx, fy, fz](x, y, z, vx, vy, vz, t, m), with named "
      "constants and an optional potential U";
  pdyn::ParamSpec constants =
      pdyn::param::optional("constants", pdyn::ParamType::NamedReals, "",
                            "named constants for the expressions, e.g. { k: 4.0, w: 2.0 }");
  constants.fallback = pdyn::NamedReals{};
  d.params = {
      pdyn::param::required("force", pdyn::ParamType::StringList, "N",
                            "three expressions [fx, fy, fz] in x y z (m), vx vy vz (m/s), t (s), "
                            "m (kg) and the constants")
          .with_sample(std::vector<std::string>{"-k*x", "-k*y + w*m", "-k*z"}),
      constants.with_sample(pdyn::NamedReals{{"k", 4.0}, {"w", 2.0}}),
      pdyn::param::optional("potential", pdyn::ParamType::String, "J",
                            "potential energy per particle U(x, y, z, t, m), if f = -grad U; "
                            "default: none reported")
          .with_sample(std::string("k*(x^2 + y^2 + z^2)/2 - w*m*y")),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.create_force = create;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
