// Edit distance and nearest-name suggestions (suggest.h).
#include "tactforce/io/suggest.h"

#include <algorithm>
#include <numeric>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace tactforce::io {

int EditDistance(std::string_view a, std::string_view b) {
  const size_t n = a.size(), m = b.size();
  // Three rows of the dynamic programme: i - 2, i - 1, i.
  std::vector<int> two_back(m + 1), previous(m + 1), current(m + 1);
  std::iota(previous.begin(), previous.end(), 0);
  for (size_t i = 1; i <= n; ++i) {
    current[0] = static_cast<int>(i);
    const char ai = absl::ascii_tolower(static_cast<unsigned char>(a[i - 1]));
    for (size_t j = 1; j <= m; ++j) {
      const char bj = absl::ascii_tolower(static_cast<unsigned char>(b[j - 1]));
      int best =
          std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ai == bj ? 0 : 1)});
      if (i > 1 && j > 1 && ai == absl::ascii_tolower(static_cast<unsigned char>(b[j - 2])) &&
          absl::ascii_tolower(static_cast<unsigned char>(a[i - 2])) == bj) {
        best = std::min(best, two_back[j - 2] + 1);
      }
      current[j] = best;
    }
    two_back.swap(previous);
    previous.swap(current);
  }
  return previous[m];
}

std::vector<std::string> NearestNames(std::string_view name,
                                      const std::vector<std::string>& candidates, int limit) {
  const int within = std::max<int>(2, static_cast<int>(name.size()) / 3);
  std::vector<std::pair<int, size_t>> near;  // (distance, candidate index)
  for (size_t k = 0; k < candidates.size(); ++k) {
    const int d = EditDistance(name, candidates[k]);
    if (d <= within) near.emplace_back(d, k);
  }
  std::stable_sort(near.begin(), near.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  // Only the nearest few: with a long shared prefix ("CONE_MODEL_") a far
  // name can still be within the limit.
  std::vector<std::string> out;
  for (size_t k = 0; k < near.size() && static_cast<int>(out.size()) < limit &&
                     near[k].first <= near[0].first + 1;
       ++k) {
    out.push_back(candidates[near[k].second]);
  }
  return out;
}

std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates) {
  if (candidates.empty()) return "";
  const std::vector<std::string> near = NearestNames(name, candidates);
  if (near.empty()) return absl::StrCat("; expected one of: ", absl::StrJoin(candidates, ", "));
  std::string out = "; did you mean ";
  for (size_t k = 0; k < near.size(); ++k) {
    absl::StrAppend(&out, k == 0 ? "" : (k + 1 == near.size() ? " or " : ", "), "'", near[k], "'");
  }
  return absl::StrCat(out, "?");
}

}  // namespace tactforce::io
