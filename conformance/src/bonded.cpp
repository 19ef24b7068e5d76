// The bonded checks: what a bonded force (pdyn/bonded.hpp) must do beyond
// what every force must, one term at a time, through the optional
// interface BondedReference (pdyn/bonded_reference.hpp; found with
// dynamic_cast, as pair_checks finds PairReference). The generic force.*
// checks run at the construction state, where a bonded term built without
// `rest` is at rest and exerts nothing; these run on random states, away
// from rest:
//
//   bonded.third_law        an `internal` force's terms each sum to zero
//                           force and zero torque
//   bonded.gradient         each term's forces are minus the gradient of its
//                           energy (central differences), velocities zero
//   bonded.jacobian_exact   the law's exact Jacobians equal central
//                           differences of the term's forces, in x and v
//   bonded.jacobian_definite the Jacobians implicit solvers get are
//                           symmetric and negative semidefinite
//   bonded.matches_terms    the force's loop (blocks, boundary terms,
//                           threads) adds what its terms add, and the same
//                           bits on 1 and 2 threads, on 5,000 particles
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>

#include "checks.hpp"
#include "isolation.hpp"
#include "pdyn/bonded_reference.hpp"
#include "pdyn/host/threads.hpp"
#include "pdyn/parallel.hpp"
#include "sample.hpp"

namespace pdyn::conformance::detail {

namespace {

constexpr int kStates = 5;  // random states per check

const BondedReference* bonded_reference_of(const Force& f) {
  return dynamic_cast<const BondedReference*>(&f);
}

struct TermForces {
  double energy = 0.0;
  std::array<Vec3, 4> force{};
};

TermForces term_at(const BondedReference& b, const State& s, Index t) {
  TermForces out;
  out.energy = b.bonded_term_forces(s.view(), t, out.force);
  return out;
}

CheckResult third_law(const PluginDescriptor& d, const BondedReference& b, std::mt19937_64& rng) {
  const char* name = "bonded.third_law";
  if (!d.force_traits.internal) return skip(name, "not declared internal");
  double worst = 0.0, bound = 0.0;
  for (int round = 0; round < kStates; ++round) {
    const State s = random_state(rng);
    for (Index t = 0; t < b.bonded_terms(); ++t) {
      const auto ids = b.bonded_term(t);
      const TermForces f = term_at(b, s, t);
      Vec3 net = Vec3::Zero(), torque = Vec3::Zero();
      double scale = 0.0;
      for (int a = 0; a < b.bonded_arity(); ++a) {
        net += f.force[a];
        torque += Vec3(s.x.col(ids[a])).cross(f.force[a]);
        scale = std::max(scale, f.force[a].norm());
      }
      worst = std::max({worst, net.norm(), torque.norm()});
      bound = std::max(bound, 1e-12 * (1.0 + 4.0 * scale));
    }
  }
  return result(name, worst <= bound, worst, bound,
                fmt::format("declared internal: |sum f_a|, |sum x_a x f_a| of each term, N and N "
                            "m, on {} random states",
                            kStates));
}

CheckResult gradient(const BondedReference& b, std::mt19937_64& rng) {
  const char* name = "bonded.gradient";
  double worst = 0.0, bound = 0.0;
  for (int round = 0; round < kStates; ++round) {
    State s = random_state(rng);
    s.v.setZero();  // damping has no potential
    for (Index t = 0; t < b.bonded_terms(); ++t) {
      const auto ids = b.bonded_term(t);
      const TermForces f = term_at(b, s, t);
      double scale = 0.0;
      for (int a = 0; a < b.bonded_arity(); ++a) {
        scale = std::max(scale, f.force[a].cwiseAbs().maxCoeff());
        for (int k = 0; k < 3; ++k) {
          const double x0 = s.x(k, ids[a]), h = 1e-6;
          s.x(k, ids[a]) = x0 + h;
          const double up = term_at(b, s, t).energy;
          s.x(k, ids[a]) = x0 - h;
          const double down = term_at(b, s, t).energy;
          s.x(k, ids[a]) = x0;
          worst = std::max(worst, std::abs(f.force[a][k] + (up - down) / (2 * h)));
        }
      }
      bound = std::max(bound, 1e-6 * (1.0 + scale));
    }
  }
  return result(name, worst <= bound, worst, bound,
                fmt::format("|f_a + dU_term/dx_a (central differences, h = 1e-6 m)|_max of each "
                            "term, N, on {} random states",
                            kStates));
}

// Central differences of term t's forces in the positions (or velocities)
// of its particles: 3n x 3n.
Eigen::MatrixXd term_differences(const BondedReference& b, State& s, Index t, bool velocity) {
  const int n = b.bonded_arity();
  const auto ids = b.bonded_term(t);
  Eigen::MatrixXd out(3 * n, 3 * n);
  for (int c = 0; c < 3 * n; ++c) {
    Matrix3X& field = velocity ? s.v : s.x;
    double& x = field(c % 3, ids[c / 3]);
    const double x0 = x, h = 1e-6;
    x = x0 + h;
    const TermForces up = term_at(b, s, t);
    x = x0 - h;
    const TermForces down = term_at(b, s, t);
    x = x0;
    for (int a = 0; a < n; ++a) {
      out.block<3, 1>(3 * a, c) = (up.force[a] - down.force[a]) / (2 * h);
    }
  }
  return out;
}

CheckResult jacobian_exact(const BondedReference& b, std::mt19937_64& rng) {
  const char* name = "bonded.jacobian_exact";
  double worst = 0.0, bound = 0.0;
  for (int round = 0; round < kStates; ++round) {
    State s = random_state(rng);
    for (Index t = 0; t < b.bonded_terms(); ++t) {
      Eigen::MatrixXd dfdx, dfdv;
      if (!b.bonded_term_jacobian(s.view(), t, true, dfdx, dfdv)) {
        return skip(name, "the law gives no Jacobians");
      }
      const Eigen::MatrixXd fx = term_differences(b, s, t, false);
      const Eigen::MatrixXd fv = term_differences(b, s, t, true);
      worst =
          std::max({worst, (dfdx - fx).cwiseAbs().maxCoeff(), (dfdv - fv).cwiseAbs().maxCoeff()});
      bound = std::max(bound,
                       1e-5 * (1.0 + std::max(fx.cwiseAbs().maxCoeff(), fv.cwiseAbs().maxCoeff())));
    }
  }
  return result(name, worst <= bound, worst, bound,
                fmt::format("|df/dx, df/dv of each term - central differences (h = 1e-6)|_max, "
                            "on {} random states with velocities",
                            kStates));
}

// Largest eigenvalue of the symmetric part, and the asymmetry, of m.
double worst_definiteness(const Eigen::MatrixXd& m, double& asymmetry) {
  asymmetry = std::max(asymmetry, (m - m.transpose()).cwiseAbs().maxCoeff());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (m + m.transpose()),
                                                           Eigen::EigenvaluesOnly);
  return eig.eigenvalues().maxCoeff();
}

CheckResult jacobian_definite(const BondedReference& b, std::mt19937_64& rng) {
  const char* name = "bonded.jacobian_definite";
  double worst = 0.0, bound = 0.0;
  for (int round = 0; round < kStates; ++round) {
    const State s = random_state(rng);
    for (Index t = 0; t < b.bonded_terms(); ++t) {
      Eigen::MatrixXd dfdx, dfdv;
      if (!b.bonded_term_jacobian(s.view(), t, false, dfdx, dfdv)) {
        return skip(name, "the law gives no Jacobians for implicit solvers");
      }
      double asymmetry = 0.0;
      const double top =
          std::max(worst_definiteness(dfdx, asymmetry), worst_definiteness(dfdv, asymmetry));
      worst = std::max({worst, top, asymmetry});
      const double scale = std::max(dfdx.cwiseAbs().maxCoeff(), dfdv.cwiseAbs().maxCoeff());
      bound = std::max(bound, 1e-10 * (1.0 + scale));
    }
  }
  return result(name, worst <= bound, worst, bound,
                fmt::format("largest eigenvalue and |J - J^T|_max of each term's df/dx and df/dv "
                            "for implicit solvers (<= 0 and 0), on {} random states",
                            kStates));
}

// A chain of terms over consecutive particles plus terms joining far-apart
// particles, so that the loop has interior and boundary terms in several
// blocks.
std::vector<std::array<Index, 4>> many_terms(int arity, Index n, Index count,
                                             std::mt19937_64& rng) {
  std::uniform_int_distribution<Index> pick(0, n - 1);
  std::vector<std::array<Index, 4>> out;
  for (Index t = 0; static_cast<Index>(out.size()) < count; ++t) {
    std::array<Index, 4> ids{-1, -1, -1, -1};
    if (t < n - arity) {
      for (int a = 0; a < arity; ++a) ids[a] = t + a;
    } else {
      for (int a = 0; a < arity; ++a) {
        Index i;
        do {
          i = pick(rng);
        } while (std::find(ids.begin(), ids.begin() + a, i) != ids.begin() + a);
        ids[a] = i;
      }
    }
    out.push_back(ids);
  }
  return out;
}

// Params with the term list `key` replaced by `terms`.
Params with_terms(Params p, const ParamSpec& key, int arity,
                  const std::vector<std::array<Index, 4>>& terms) {
  auto copy = [&](auto tag) {
    using Tuple = decltype(tag);
    std::vector<Tuple> v(terms.size());
    for (std::size_t t = 0; t < terms.size(); ++t) {
      for (int a = 0; a < arity; ++a) v[t][a] = terms[t][a];
    }
    p.set(key.name, std::move(v));
  };
  if (arity == 2) copy(IndexPair{});
  if (arity == 3) copy(IndexTriple{});
  if (arity == 4) copy(IndexQuad{});
  return p;
}

CheckResult matches_terms(const PluginDescriptor& d, const Params& params,
                          const BondedReference& home, std::mt19937_64& rng) {
  const char* name = "bonded.matches_terms";
  const int arity = home.bonded_arity();
  const ParamType wanted = arity == 2   ? ParamType::IndexPairs
                           : arity == 3 ? ParamType::IndexTriples
                                        : ParamType::IndexQuads;
  const auto key = std::find_if(d.params.begin(), d.params.end(),
                                [&](const ParamSpec& s) { return s.type == wanted; });
  if (key == d.params.end()) {
    return skip(name, fmt::format("no parameter of type {} to give it terms", type_name(wanted)));
  }
  constexpr Index kN = 5000, kTerms = 8192;
  const State built = random_state(rng, kN);
  const Params p = with_terms(params, *key, arity, many_terms(arity, kN, kTerms, rng));
  const std::shared_ptr<Force> force(d.create_force(p, context_of(built)));
  const auto* b = bonded_reference_of(*force);
  if (!b) return result(name, false, 1, 0, "the object built with many terms is not bonded");
  const State s = random_state(rng, kN);  // away from rest
  Matrix3X sum = Matrix3X::Zero(3, kN);
  double energy = 0.0;
  for (Index t = 0; t < b->bonded_terms(); ++t) {
    const auto ids = b->bonded_term(t);
    const TermForces f = term_at(*b, s, t);
    for (int a = 0; a < arity; ++a) sum.col(ids[a]) += f.force[a];
    energy += f.energy;
  }
  const int before = max_threads();
  set_threads(1);
  const Matrix3X one = forces_of(*force, s);
  // In a child of a process that already ran threads, a team would hang
  // it (threads_usable()): one thread only, said in the detail.
  const bool threaded = threads_usable();
  if (threaded) set_threads(2);
  const Matrix3X two = forces_of(*force, s);
  set_threads(before);
  const double u = force->potential_energy(s.view()).value_or(energy);
  const double err = std::max((one - sum).cwiseAbs().maxCoeff() / (1.0 + max_abs(sum)),
                              std::abs(u - energy) / (1.0 + std::abs(energy)));
  const bool same_bits = bit_equal(one, two);
  const double bound = 1e-12;
  return result(name, err <= bound && same_bits, same_bits ? err : 1.0, bound,
                fmt::format("{} terms on {} particles: |loop - sum of terms| / (1 + |sum|) for f "
                            "and U; 1 and 2 threads {}",
                            b->bonded_terms(), kN,
                            !threaded   ? "not compared (a child of a threaded process: run "
                                          "`pdyn check` to compare them)"
                            : same_bits ? "bit-identical"
                                        : "DIFFER"));
}

}  // namespace

void bonded_checks(const PluginDescriptor& d, const Params& params, const Force& force,
                   std::mt19937_64& rng, std::vector<CheckResult>& out) {
  const BondedReference* b = bonded_reference_of(force);
  const char* names[] = {"bonded.third_law", "bonded.gradient", "bonded.jacobian_exact",
                         "bonded.jacobian_definite", "bonded.matches_terms"};
  if (!b) {
    for (const char* name : names) {
      out.push_back(skip(name,
                         "not a bonded force (offers no pdyn::BondedReference, "
                         "pdyn/bonded.hpp)"));
    }
    return;
  }
  guarded(out, names[0], [&] { return third_law(d, *b, rng); });
  guarded(out, names[1], [&] { return gradient(*b, rng); });
  guarded(out, names[2], [&] { return jacobian_exact(*b, rng); });
  guarded(out, names[3], [&] { return jacobian_definite(*b, rng); });
  guarded(out, names[4], [&] { return matches_terms(d, params, *b, rng); });
}

}  // namespace pdyn::conformance::detail
