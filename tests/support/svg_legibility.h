// Legibility checks for the project's SVG pictures, shared by the tests of
// every layer that draws one: the SVG is parsed back, each <text>'s box is
// estimated from its font size and character count (0.6 em per code point,
// 0.8 em above the baseline, 0.25 em below; rotate(-90) turns it), and
// ExpectLegible checks that no two boxes overlap, every box lies inside the
// canvas, and every labelled axis (<g class="x-ticks|y-ticks|bar-ticks">)
// has at least three tick labels.
#pragma once

#include <algorithm>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace tactforce::test_support {

struct Label {
  std::string text;
  double left, top, right, bottom;  // px, estimated
};

struct Parsed {
  double width = 0, height = 0;
  std::vector<Label> labels;
  std::vector<int> tick_groups;  // tick labels per x-ticks / y-ticks / bar-ticks group
};

inline double Attribute(const std::string& tag, const std::string& name, double fallback) {
  std::smatch m;
  if (std::regex_search(tag, m, std::regex("\\s" + name + "=\"([-0-9.e+]+)\"")))
    return std::stod(m[1]);
  return fallback;
}

inline std::string Unescape(std::string s) {
  for (const auto& [entity, c] : std::vector<std::pair<std::string, std::string>>{
           {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&#39;", "'"}, {"&amp;", "&"}}) {
    for (size_t p = s.find(entity); p != std::string::npos; p = s.find(entity, p))
      s.replace(p, entity.size(), c);
  }
  return s;
}

// The test's own estimate: 0.6 em per code point, 0.8 em above the baseline
// and 0.25 em below; a rotate(-90) turns the box about (x, y).
inline Label BoxOf(const std::string& tag, const std::string& text, double default_size) {
  const double x = Attribute(tag, "x", 0), y = Attribute(tag, "y", 0),
               size = Attribute(tag, "font-size", default_size);
  size_t chars = 0;
  for (char c : text) chars += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
  const double w = 0.6 * size * chars;
  const double start = tag.find("text-anchor=\"middle\"") != std::string::npos ? -w / 2
                       : tag.find("text-anchor=\"end\"") != std::string::npos  ? -w
                                                                               : 0;
  if (tag.find("rotate(-90") != std::string::npos)
    return {text, x - 0.8 * size, y - start - w, x + 0.25 * size, y - start};
  return {text, x + start, y - 0.8 * size, x + start + w, y + 0.25 * size};
}

inline Parsed Parse(const std::string& svg) {
  Parsed p;
  std::smatch root;
  EXPECT_TRUE(std::regex_search(svg, root, std::regex("<svg[^>]*>")));
  const std::string root_tag = root[0];
  p.width = Attribute(root_tag, "width", 0);
  p.height = Attribute(root_tag, "height", 0);
  const double font = Attribute(root_tag, "font-size", 16);
  const std::regex text("(<text[^>]*>)([^<]*)</text>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), text); it != std::sregex_iterator();
       ++it)
    p.labels.push_back(BoxOf((*it)[1], Unescape((*it)[2]), font));
  const std::regex group("<g class=\"(x|y|bar)-ticks\">([\\s\\S]*?)</g>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), group); it != std::sregex_iterator();
       ++it) {
    const std::string body = (*it)[2];
    int n = 0;
    for (size_t q = body.find("<text"); q != std::string::npos; q = body.find("<text", q + 1)) ++n;
    p.tick_groups.push_back(n);
  }
  return p;
}

// The three checks; `what` names the picture in failures.
inline void ExpectLegible(const std::string& svg, const std::string& what) {
  const Parsed p = Parse(svg);
  ASSERT_GT(p.width, 0) << what;
  ASSERT_FALSE(p.labels.empty()) << what;
  for (const Label& l : p.labels) {
    EXPECT_TRUE(l.left >= -0.5 && l.top >= -0.5 && l.right <= p.width + 0.5 &&
                l.bottom <= p.height + 0.5)
        << what << ": \"" << l.text << "\" [" << l.left << ", " << l.top << ", " << l.right << ", "
        << l.bottom << "] outside the " << p.width << " x " << p.height << " canvas";
  }
  for (size_t i = 0; i < p.labels.size(); ++i)
    for (size_t j = i + 1; j < p.labels.size(); ++j) {
      const Label &a = p.labels[i], &b = p.labels[j];
      const double dx = std::min(a.right, b.right) - std::max(a.left, b.left);
      const double dy = std::min(a.bottom, b.bottom) - std::max(a.top, b.top);
      EXPECT_FALSE(dx > 0.5 && dy > 0.5)
          << what << ": \"" << a.text << "\" overlaps \"" << b.text << "\"";
    }
  int labelled_axes = 0;
  for (int n : p.tick_groups) {
    if (n == 0) continue;  // an axis without labels (shared with the panel below)
    ++labelled_axes;
    EXPECT_GE(n, 3) << what << ": an axis with " << n << " tick labels";
  }
  EXPECT_GE(labelled_axes, 2) << what;
}

}  // namespace tactforce::test_support
