// lennard_jones: the 12-6 Lennard-Jones pair potential (Jones 1924; the
// form of LAMMPS's pair style lj/cut), cut off at rc and optionally shifted
// so that U(rc) = 0:
//
//   U(r) = 4 eps [ (sigma/r)^12 - (sigma/r)^6 ] - U_shift,   r < rc
//   F_ij = 24 eps [ 2 (sigma/r)^12 - (sigma/r)^6 ] / r^2 (x_i - x_j)
//
// with U_shift = 4 eps [ (sigma/rc)^12 - (sigma/rc)^6 ] when `shift` is on,
// else 0 (the force is the same either way: shifting only moves the energy).
// The loop, neighbor list, threads and periodic images are the kernel's
// (pdyn/pair.hpp); this file is the law. It is evaluated as LAMMPS does,
// r6inv (lj1 r6inv - lj2) r2inv with lj1 = 48 eps sigma^12 and
// lj2 = 24 eps sigma^6, so that the two programs round alike.
//
// Mixtures. eps, sigma and rc may depend on the types of the two particles
// (ParticleView::type), as LAMMPS's `pair_coeff I J eps sigma [rc]` lines
// and `pair_modify mix` give them: `pair_coeff` rows, and a mixing rule for
// the cross pairs I J no row gives, from the self pairs I I and J J
// (geometric: eps = sqrt(eps_I eps_J), sigma = sqrt(sigma_I sigma_J),
// rc = sqrt(rc_I rc_J); arithmetic, Lorentz-Berthelot: the same eps,
// sigma = (sigma_I + sigma_J) / 2, rc = (rc_I + rc_J) / 2). Without rows
// there is one set of coefficients and the law never reads the types: the
// one-type law below is the one LAMMPS's melt benchmark runs, unchanged.
// With rows, the law looks its pair's coefficients up in a small table
// indexed by the two types (flattened, 48 bytes per pair of types).
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <pdyn/pair.hpp>
#include <pdyn/plugin.hpp>
#include <pdyn/selection.hpp>
#include <sstream>

namespace {

// The largest type a `pair_coeff` table holds: 256^2 pairs of 48 bytes
// (3 MB) at most. Mixtures have a handful of types.
constexpr std::int32_t kMaxType = 255;

// One pair of types' coefficients in the form the law evaluates.
struct Coefficients {
  double lj1 = 0, lj2 = 0, lj3 = 0, lj4 = 0;  // 48 eps s^12, 24 eps s^6, 4 eps s^12, 4 eps s^6
  double offset = 0;                          // U_shift, J
  double cutoff2 = 0;                         // rc^2, m^2; 0: the pair does not interact

  Coefficients() = default;
  Coefficients(double epsilon, double sigma, double cutoff, bool shift) {
    const double s6 = std::pow(sigma, 6.0), s12 = s6 * s6;
    lj1 = 48.0 * epsilon * s12;
    lj2 = 24.0 * epsilon * s6;
    lj3 = 4.0 * epsilon * s12;
    lj4 = 4.0 * epsilon * s6;
    const double rc6inv = 1.0 / std::pow(cutoff, 6.0);
    offset = shift ? rc6inv * (lj3 * rc6inv - lj4) : 0.0;
    cutoff2 = cutoff * cutoff;
  }

  [[gnu::always_inline]] inline pdyn::PairTerm at(double r2) const {
    const double r2inv = 1.0 / r2;
    const double r6inv = r2inv * r2inv * r2inv;
    return {r6inv * (lj3 * r6inv - lj4) - offset, r6inv * (lj1 * r6inv - lj2) * r2inv};
  }
  // d/d(r^2) of -U'(r)/r = lj1 r^-14 - lj2 r^-8: -7 lj1 r^-16 + 4 lj2 r^-10,
  // for the analytic Jacobians of implicit solvers.
  double slope(double r2) const {
    const double r2inv = 1.0 / r2;
    const double r6inv = r2inv * r2inv * r2inv;
    return r2inv * r2inv * r6inv * (4.0 * lj2 - 7.0 * lj1 * r6inv);
  }
};

// One set of coefficients for every pair (no `pair_coeff`): the types are
// never read, and the pair loop's cutoff is the law's.
struct LennardJones {
  Coefficients c;
  bool shift;
  // Finite and cheap at every r2 > 0: the force loop evaluates every listed
  // pair and selects those within the cutoff (pdyn/pair.hpp).
  static constexpr bool evaluate_beyond_cutoff = true;

  pdyn::PairTerm operator()(double r2, std::int32_t, std::int32_t) const { return c.at(r2); }
  double force_over_r_slope(double r2, std::int32_t, std::int32_t) const { return c.slope(r2); }
  bool continuous_at_cutoff() const { return shift; }
};

// Coefficients per pair of types. The table has n + 1 rows and columns for
// the types 0..n-1 and one more, with no interaction, where any type the
// table does not hold lands (a particle added later with a new type): one
// compare per type, no branch on the table's size.
struct LennardJonesTypes {
  std::vector<Coefficients> table;  // (n + 1)^2, row-major by the first type
  std::uint32_t n = 0;
  bool shift = false;

  [[gnu::always_inline]] inline std::size_t slot(std::int32_t t) const {
    return std::min(static_cast<std::uint32_t>(t), n);
  }
  // A select, not a branch, on the pair's own cutoff: the force loop calls
  // the law on every listed pair (evaluate_beyond_cutoff), where about a
  // third lie beyond it in no predictable order.
  static constexpr bool evaluate_beyond_cutoff = true;
  pdyn::PairTerm operator()(double r2, std::int32_t ti, std::int32_t tj) const {
    const Coefficients& c = table[slot(ti) * (n + 1) + slot(tj)];
    const pdyn::PairTerm t = c.at(r2);
    const bool within = r2 < c.cutoff2;
    return {within ? t.energy : 0.0, within ? t.force_over_r : 0.0};
  }
  double force_over_r_slope(double r2, std::int32_t ti, std::int32_t tj) const {
    const Coefficients& c = table[slot(ti) * (n + 1) + slot(tj)];
    if (!(r2 < c.cutoff2)) return 0.0;
    return c.slope(r2);
  }
  bool continuous_at_cutoff() const { return shift; }
};

// ---- the `pair_coeff` rows ----

enum class Mix { Geometric, Arithmetic, None };

// A pair's coefficients as the scene gives them, and where.
struct Pair {
  double epsilon, sigma, cutoff;
  long row = -1;  // the `pair_coeff` row giving it, -1 if mixed or the fallback
};

struct Row {
  std::int32_t i, j;
  Pair pair;
};

[[noreturn]] void row_error(const std::string& text, long index, const std::string& what) {
  throw pdyn::ParamError("pair_coeff", fmt::format("'{}': {}", text, what), index);
}

// "I J epsilon sigma [cutoff]", whitespace-separated, as a LAMMPS pair_coeff line.
Row parse_row(const std::string& text, long index, double default_cutoff) {
  std::istringstream in(text);
  std::vector<std::string> field;
  for (std::string w; in >> w;) field.push_back(w);
  if (field.size() != 4 && field.size() != 5) {
    row_error(text, index,
              fmt::format("{} fields (expected 'I J epsilon sigma' or 'I J epsilon sigma cutoff': "
                          "two types, then numbers in J and m)",
                          field.size()));
  }
  auto type = [&](const std::string& w) {
    std::int32_t t = -1;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), t);
    if (ec != std::errc{} || end != w.data() + w.size() || t < 0 || t > kMaxType) {
      row_error(text, index,
                fmt::format("'{}' is not a type (expected a whole number in 0..{})", w, kMaxType));
    }
    return t;
  };
  auto number = [&](const std::string& w, const char* name) {
    double x = 0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), x);
    if (ec != std::errc{} || end != w.data() + w.size() || !std::isfinite(x)) {
      row_error(text, index, fmt::format("{} '{}' is not a number", name, w));
    }
    return x;
  };
  Row r{type(field[0]), type(field[1]), {}};
  r.pair.epsilon = number(field[2], "epsilon");
  r.pair.sigma = number(field[3], "sigma");
  r.pair.cutoff = field.size() == 5 ? number(field[4], "cutoff") : default_cutoff;
  r.pair.row = index;
  if (r.pair.epsilon < 0) {
    row_error(text, index,
              fmt::format("epsilon {} J is negative (expected epsilon >= 0 J)", r.pair.epsilon));
  }
  if (!(r.pair.sigma > 0)) {
    row_error(text, index, fmt::format("sigma {} m (expected sigma > 0 m)", r.pair.sigma));
  }
  if (!(r.pair.cutoff > 0)) {
    row_error(text, index, fmt::format("cutoff {} m (expected cutoff > 0 m)", r.pair.cutoff));
  }
  return r;
}

Mix parse_mix(const std::string& s) {
  if (s == "geometric") return Mix::Geometric;
  if (s == "arithmetic") return Mix::Arithmetic;
  if (s == "none") return Mix::None;
  throw pdyn::ParamError(
      "mix", fmt::format("'{}' is not a mixing rule (expected geometric, arithmetic or none)", s));
}

Pair mix(const Pair& a, const Pair& b, Mix rule) {
  const double epsilon = std::sqrt(a.epsilon * b.epsilon);
  if (rule == Mix::Geometric) {
    return {epsilon, std::sqrt(a.sigma * b.sigma), std::sqrt(a.cutoff * b.cutoff)};
  }
  return {epsilon, 0.5 * (a.sigma + b.sigma), 0.5 * (a.cutoff + b.cutoff)};
}

// How many particles of each type take part, up to 2 (a pair of them), for
// the types 0..top; `top` grows to the largest type among them.
std::vector<int> type_counts(const pdyn::ParticleView& particles,
                             const std::vector<std::uint8_t>& members, std::int32_t& top) {
  std::vector<int> count;
  for (pdyn::Index i = 0; i < particles.size(); ++i) {
    if (!members.empty() && members[static_cast<std::size_t>(i)] == 0) continue;
    const std::int32_t t = particles.type.empty() ? 0 : particles.type[static_cast<std::size_t>(i)];
    if (t > kMaxType) {
      throw pdyn::ParamError("pair_coeff",
                             fmt::format("particle {} has type {} (expected types 0..{} with "
                                         "pair_coeff, a table of every pair of types)",
                                         i, t, kMaxType));
    }
    if (static_cast<std::size_t>(t) >= count.size()) count.resize(static_cast<std::size_t>(t) + 1);
    count[static_cast<std::size_t>(t)] = std::min(2, count[static_cast<std::size_t>(t)] + 1);
    top = std::max(top, t);
  }
  count.resize(static_cast<std::size_t>(top) + 1);
  return count;
}

// The per-type law from the rows, for the particles the scene starts with
// (their types must all be covered), and the pair loop's cutoff: the
// largest of the table's.
struct TypedSetup {
  LennardJonesTypes law;
  double cutoff = 0;
  long cutoff_row = -1;  // the row giving that cutoff, or -1
};

TypedSetup typed_setup(const pdyn::Params& p, const pdyn::ParticleView& particles,
                       const std::vector<std::uint8_t>& members) {
  const double default_cutoff = p.real("cutoff");
  const Mix rule = parse_mix(p.string("mix"));
  const auto& text = p.strings("pair_coeff");
  std::vector<Row> rows;
  std::int32_t top = 0;
  for (std::size_t k = 0; k < text.size(); ++k) {
    rows.push_back(parse_row(text[k], static_cast<long>(k), default_cutoff));
    top = std::max({top, rows.back().i, rows.back().j});
  }
  const std::vector<int> count = type_counts(particles, members, top);

  const auto n = static_cast<std::size_t>(top) + 1;
  std::vector<std::optional<Pair>> given(n * n);
  for (const Row& r : rows) {
    auto& at = given[static_cast<std::size_t>(r.i) * n + static_cast<std::size_t>(r.j)];
    if (at) {
      row_error(
          text[static_cast<std::size_t>(r.pair.row)], r.pair.row,
          fmt::format("the pair {} {} is given again (first in row {}: '{}')", std::min(r.i, r.j),
                      std::max(r.i, r.j), at->row, text[static_cast<std::size_t>(at->row)]));
    }
    at = r.pair;
    given[static_cast<std::size_t>(r.j) * n + static_cast<std::size_t>(r.i)] = r.pair;
  }
  // epsilon and sigma, when the scene gives either: the pairs left out.
  std::optional<Pair> fallback;
  if (p.has("epsilon") || p.has("sigma")) {
    fallback = Pair{p.has("epsilon") ? p.real("epsilon") : 1.0,
                    p.has("sigma") ? p.real("sigma") : 1.0, default_cutoff};
  }
  auto self = [&](std::size_t t) { return given[t * n + t] ? given[t * n + t] : fallback; };
  auto pair = [&](std::size_t a, std::size_t b) -> std::optional<Pair> {
    if (given[a * n + b]) return given[a * n + b];
    if (a != b && rule != Mix::None && self(a) && self(b)) return mix(*self(a), *self(b), rule);
    return fallback;
  };

  TypedSetup s;
  s.law.n = static_cast<std::uint32_t>(n);
  s.law.shift = p.boolean("shift");
  s.law.table.assign((n + 1) * (n + 1), Coefficients{});
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      const auto c = pair(a, b);
      const bool formed = a == b ? count[a] >= 2 : count[a] >= 1 && count[b] >= 1;
      if (!c) {
        if (!formed) continue;  // no particles of these types: no interaction
        throw pdyn::ParamError(
            "pair_coeff",
            fmt::format("no coefficients for the type pair {} {}, which the scene's particles "
                        "form (expected a row '{} {} epsilon sigma'{}, or epsilon and sigma for "
                        "the pairs without a row)",
                        a, b, a, b,
                        a == b ? ""
                        : rule == Mix::None
                            ? " (mix: none)"
                            : fmt::format(" or rows for {} {} and {} {} to mix", a, a, b, b)));
      }
      s.law.table[a * (n + 1) + b] = Coefficients(c->epsilon, c->sigma, c->cutoff, s.law.shift);
      if (c->cutoff > s.cutoff) {
        s.cutoff = c->cutoff;
        s.cutoff_row = c->row;
      }
    }
  }
  return s;
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Force;
  d.name = "lennard_jones";
  d.version = "1.1.0";
  d.description =
      "12-6 Lennard-Jones pair potential U = 4 eps [(sigma/r)^12 - (sigma/r)^6] within a cutoff, "
      "optionally shifted to U(rc) = 0; coefficients per pair of particle types as LAMMPS's "
      "pair_coeff";
  d.params = {
      pdyn::param::optional("epsilon", pdyn::ParamType::Real, "J",
                            "depth of the potential well (1 J if not given); with pair_coeff: of "
                            "the pairs no row or mixing gives")
          .greater_than(0),
      pdyn::param::optional("sigma", pdyn::ParamType::Real, "m",
                            "distance at which U = 0 (1 m if not given); with pair_coeff: of the "
                            "pairs no row or mixing gives")
          .greater_than(0),
      pdyn::param::real("cutoff", 2.5, "m",
                        "no interaction beyond this distance rc (of the pair_coeff rows that give "
                        "none)")
          .greater_than(0),
      pdyn::param::boolean("shift", false, "shift the energy so that U(rc) = 0 (for every pair)"),
      pdyn::param::real("skin", 0.3, "m", "neighbor-list skin: rebuilt after a move of skin/2")
          .at_least(0),
      pdyn::param::optional("pair_coeff", pdyn::ParamType::StringList, "",
                            "coefficients per pair of types, rows 'I J epsilon sigma [cutoff]' "
                            "(J, m) as LAMMPS's pair_coeff"),
      pdyn::param::string("mix", "geometric",
                          "the cross pairs I J no row gives, from I I and J J: geometric, "
                          "arithmetic (Lorentz-Berthelot) or none"),
  };
  for (auto& s : pdyn::selection_params()) d.params.push_back(std::move(s));
  d.force_traits.internal = true;  // central pair forces: momentum and angular momentum kept
  d.force_traits.singular = true;  // U -> infinity as r -> 0
  d.create_force = [](const pdyn::Params& p,
                      const pdyn::SceneContext& ctx) -> std::unique_ptr<pdyn::Force> {
    const double skin = p.real("skin");
    const bool shift = p.boolean("shift");
    parse_mix(p.string("mix"));  // refused even where no row needs it
    const pdyn::Selection selection = pdyn::Selection::from_params(p, ctx);
    std::vector<std::uint8_t> members = selection.mask(ctx.particles.size());
    if (!p.has("pair_coeff") || p.strings("pair_coeff").empty()) {
      const double cutoff = p.real("cutoff");
      pdyn::check_cutoff_fits(ctx.particles.domain, cutoff, skin);
      const double epsilon = p.has("epsilon") ? p.real("epsilon") : 1.0;
      const double sigma = p.has("sigma") ? p.real("sigma") : 1.0;
      return std::make_unique<pdyn::PairForce<LennardJones>>(
          LennardJones{Coefficients(epsilon, sigma, cutoff, shift), shift}, cutoff, skin,
          std::move(members));
    }
    TypedSetup s = typed_setup(p, ctx.particles, members);
    try {
      pdyn::check_cutoff_fits(ctx.particles.domain, s.cutoff, skin);
    } catch (const pdyn::ParamError& e) {
      if (s.cutoff_row < 0 && s.cutoff == p.real("cutoff")) throw;
      throw pdyn::ParamError("pair_coeff", fmt::format("the largest cutoff, {}", e.what()),
                             s.cutoff_row);
    }
    return std::make_unique<pdyn::PairForce<LennardJonesTypes>>(std::move(s.law), s.cutoff, skin,
                                                                std::move(members));
  };
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
