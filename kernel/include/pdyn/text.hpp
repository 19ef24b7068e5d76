// pdyn/text.hpp — small text helpers for messages: a plugin's (the field
// force's "did you mean" for a function name, soft_contact's list of models), the
// kernel's and the host's, so that every message spells counts, lists and
// suggestions the same way.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "pdyn/export.hpp"

namespace pdyn {

/// Levenshtein distance between two words.
PDYN_API std::size_t edit_distance(std::string_view a, std::string_view b);
/// The candidate closest to `word`, if close enough to be a likely typo; else "".
PDYN_API std::string closest_match(std::string_view word,
                                   const std::vector<std::string>& candidates);
/// "1 particle", "3 particles": a count with its noun, in the singular for 1.
/// `plural` defaults to `singular` + "s".
PDYN_API std::string count_of(long long n, std::string_view singular, std::string_view plural = {});
/// "a, b, c"
PDYN_API std::string join(const std::vector<std::string>& words, std::string_view sep = ", ");

}  // namespace pdyn
