// The top of the conformance kit: run_checks, which runs the checks of a
// descriptor's kind in sequence (in-process or isolated, isolation.hpp), the
// helpers every check builds its result with, the check of every kind
// "descriptor.complete", and the report formats (text table, JUnit XML).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <random>

#include "checks.hpp"
#include "isolation.hpp"
#include "sample.hpp"

namespace pdyn::conformance {

// ---- results ----

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::Pass:
      return "pass";
    case Verdict::Fail:
      return "FAIL";
    case Verdict::Skip:
      return "skip";
  }
  return "?";
}

namespace detail {

CheckResult result(std::string name, bool pass, double measured, double bound, std::string detail) {
  return {std::move(name), pass ? Verdict::Pass : Verdict::Fail, measured, bound,
          std::move(detail)};
}

CheckResult skip(std::string name, std::string why) {
  return {std::move(name), Verdict::Skip, 0.0, 0.0, std::move(why)};
}

void guarded(std::vector<CheckResult>& out, const std::string& name,
             const std::function<CheckResult()>& check) {
  Worker* worker = current_worker();
  if (worker) {
    if (const CheckResult* recorded = worker->begin(out, name)) {
      out.push_back(*recorded);
      return;
    }
  }
  try {
    out.push_back(check());
  } catch (const std::exception& e) {
    out.push_back(result(name, false, 0, 0, fmt::format("threw: {}", e.what())));
  } catch (...) {
    out.push_back(result(name, false, 0, 0, "threw a non-standard exception"));
  }
  if (worker) worker->flush(out);
}

}  // namespace detail

// ---- the checks of a kind, in sequence ----

namespace {

using detail::guarded;
using detail::result;

CheckResult check_descriptor(const PluginDescriptor& d) {
  std::vector<std::string> missing;
  if (d.name.empty()) missing.push_back("name");
  if (d.version.empty()) missing.push_back("version");
  if (d.description.empty()) missing.push_back("description");
  for (const auto& p : d.params) {
    if (p.doc.empty()) missing.push_back(fmt::format("doc of parameter '{}'", p.name));
  }
  return result("descriptor.complete", missing.empty(), static_cast<double>(missing.size()), 0,
                missing.empty() ? "name, version, description and every parameter's doc given"
                                : fmt::format("missing: {}", fmt::join(missing, ", ")));
}

void check_sequence(const PluginDescriptor& d, const Options& o, std::vector<CheckResult>& out) {
  out.push_back(check_descriptor(d));
  try {
    switch (d.kind) {
      case PluginKind::Force:
        detail::force_checks(d, o, out);
        break;
      case PluginKind::Solver:
        detail::solver_checks(d, o, out);
        break;
      case PluginKind::Collider:
        detail::collider_checks(d, o, out);
        break;
      case PluginKind::Writer:
        // Files, not physics: two systems do not apply (writers.cpp
        // checks their own), a scene of bad values does.
        detail::writer_checks(d, o, out);
        break;
      case PluginKind::Constraint:
        detail::constraint_checks(d, o, out);
        break;
    }
    // Only for a plugin that can be built at all: the rest would fail for
    // the same reason as construct.defaults.
    const bool constructed = std::any_of(out.begin(), out.end(), [](const CheckResult& r) {
      return r.name == "construct.defaults" && r.verdict == Verdict::Pass;
    });
    if (constructed) {
      guarded(out, "params.bad_rejected", [&] {
        std::mt19937_64 rng(o.seed);
        return detail::check_bad_params(d, sample_params(d, detail::kParticles),
                                        detail::random_state(rng).x);
      });
      if (d.kind != PluginKind::Writer) {
        guarded(out, "threads.two_systems", [&] { return detail::check_threads(d, o); });
      }
    }
  } catch (const std::exception& e) {
    out.push_back(result("run", false, 0, 0, fmt::format("threw: {}", e.what())));
  }
}

}  // namespace

std::vector<CheckResult> run_checks(const PluginDescriptor& d, const Options& o) {
  if (o.isolate) {
    return detail::run_isolated([&](std::vector<CheckResult>& out) { check_sequence(d, o, out); },
                                o.timeout);
  }
  std::vector<CheckResult> out;
  check_sequence(d, o, out);
  return out;
}

// ---- the report ----

bool all_passed(const std::vector<CheckResult>& results) {
  return std::none_of(results.begin(), results.end(),
                      [](const CheckResult& r) { return r.verdict == Verdict::Fail; });
}

std::string table(const std::vector<CheckResult>& results) {
  std::size_t w = 5;
  for (const auto& r : results) w = std::max(w, r.name.size());
  std::string s = fmt::format("{:<{}}  {:<7} {:>11} {:>11}  {}\n", "CHECK", w, "VERDICT",
                              "MEASURED", "BOUND", "DETAIL");
  for (const auto& r : results) {
    if (r.verdict == Verdict::Skip) {
      s += fmt::format("{:<{}}  {:<7} {:>11} {:>11}  {}\n", r.name, w, verdict_name(r.verdict), "-",
                       "-", r.detail);
    } else {
      s += fmt::format("{:<{}}  {:<7} {:>11.3g} {:>11.3g}  {}\n", r.name, w,
                       verdict_name(r.verdict), r.measured, r.bound, r.detail);
    }
  }
  return s;
}

namespace {
std::string xml_escape(const std::string& in) {
  std::string out;
  for (char ch : in) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}
}  // namespace

std::string junit_xml(const PluginDescriptor& d, const std::vector<CheckResult>& results) {
  const auto failures = std::count_if(results.begin(), results.end(),
                                      [](const auto& r) { return r.verdict == Verdict::Fail; });
  const auto skipped = std::count_if(results.begin(), results.end(),
                                     [](const auto& r) { return r.verdict == Verdict::Skip; });
  std::string s = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  s += fmt::format(
      "<testsuite name=\"pdyn.check.{}\" tests=\"{}\" failures=\"{}\" skipped=\"{}\">\n",
      xml_escape(d.name), results.size(), failures, skipped);
  for (const auto& r : results) {
    s += fmt::format("  <testcase classname=\"{}.{}\" name=\"{}\"", kind_name(d.kind),
                     xml_escape(d.name), xml_escape(r.name));
    const std::string text =
        fmt::format("measured {:.6g}, bound {:.6g}: {}", r.measured, r.bound, r.detail);
    if (r.verdict == Verdict::Fail) {
      s += fmt::format(">\n    <failure message=\"{}\"/>\n  </testcase>\n", xml_escape(text));
    } else if (r.verdict == Verdict::Skip) {
      s += fmt::format(">\n    <skipped message=\"{}\"/>\n  </testcase>\n", xml_escape(r.detail));
    } else {
      s += "/>\n";
    }
  }
  return s + "</testsuite>\n";
}

}  // namespace pdyn::conformance
