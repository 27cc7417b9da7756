// "Did you mean ...?" for misspelt names (JSON fields, enum values, keys):
// the candidates nearest to a name by edit distance.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace tactforce::io {

// Optimal-string-alignment distance (insertions, deletions, substitutions
// and swaps of neighbours each cost 1), ASCII case ignored.
int EditDistance(std::string_view a, std::string_view b);

// The candidates within max(2, |name| / 3) edits of `name` and at most one
// edit farther than the nearest, nearest first (ties in candidate order); at
// most `limit`.
std::vector<std::string> NearestNames(std::string_view name,
                                      const std::vector<std::string>& candidates, int limit = 3);

// The tail of an "unknown name" message: "; did you mean 'mass'?" (or
// "'a' or 'b'") when NearestNames finds any, else "; expected one of: a, b,
// c" listing all candidates (empty when there are none).
std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace tactforce::io
