// Text extent and layout of svg.h: estimated text boxes (no font metrics
// without a renderer, so a generous 0.6 em per character), wrapping and
// shortening to a width, and label placement without overlap.
#include <algorithm>
#include <array>
#include <cmath>

#include "tactforce/io/svg.h"

namespace tactforce::io {
namespace {

constexpr double kEmPerChar = 0.6, kAscent = 0.8, kDescent = 0.25;
constexpr char kEllipsis[] = "\xe2\x80\xa6";

// UTF-8 code points of `text` (continuation bytes 10xxxxxx are not counted).
size_t CodePoints(std::string_view text) {
  return static_cast<size_t>(std::count_if(text.begin(), text.end(), [](char c) {
    return (static_cast<unsigned char>(c) & 0xc0) != 0x80;
  }));
}

// The longest prefix of `text` (whole code points) followed by "…" that fits.
std::string Shorten(std::string_view text, double size, double max_width) {
  std::string out(text);
  while (!out.empty() && TextWidth(out + kEllipsis, size) > max_width) {
    out.pop_back();
    while (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xc0) == 0x80) out.pop_back();
    if (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xc0) == 0xc0) out.pop_back();
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out + kEllipsis;
}

bool Inside(const TextBox& box, const TextBox& bounds) {
  return box.left >= bounds.left && box.right <= bounds.right && box.top >= bounds.top &&
         box.bottom <= bounds.bottom;
}

}  // namespace

double TextWidth(std::string_view text, double size) {
  return kEmPerChar * size * CodePoints(text);
}

TextBox TextBoxOf(double x, double y, std::string_view text, double size, TextAnchor anchor,
                  bool vertical) {
  const double w = TextWidth(text, size);
  const double start = anchor == TextAnchor::kStart    ? 0
                       : anchor == TextAnchor::kMiddle ? -w / 2
                                                       : -w;
  // Unrotated: along = x offsets start..start + w, across = -ascent..+descent.
  if (!vertical) return {x + start, y - kAscent * size, x + start + w, y + kDescent * size};
  // rotate(-90) about (x, y): (dx, dy) -> (dy, -dx).
  return {x - kAscent * size, y - start - w, x + kDescent * size, y - start};
}

bool Overlap(const TextBox& a, const TextBox& b, double slack) {
  return std::min(a.right, b.right) - std::max(a.left, b.left) > slack &&
         std::min(a.bottom, b.bottom) - std::max(a.top, b.top) > slack;
}

std::vector<std::string> WrapText(std::string_view text, double size, double max_width,
                                  int max_lines) {
  std::vector<std::string> lines;
  std::string line;
  size_t pos = 0;
  max_lines = std::max(1, max_lines);
  while (pos <= text.size()) {
    const size_t space = std::min(text.find(' ', pos), text.size());
    const std::string_view word = text.substr(pos, space - pos);
    const std::string joined = line.empty() ? std::string(word) : line + " " + std::string(word);
    if (line.empty() || TextWidth(joined, size) <= max_width) {
      line = joined;
    } else {
      lines.push_back(line);
      line = std::string(word);
    }
    pos = space + 1;
  }
  lines.push_back(line);
  for (std::string& l : lines)
    if (TextWidth(l, size) > max_width) l = Shorten(l, size, max_width);
  if (static_cast<int>(lines.size()) > max_lines) {
    std::string rest = lines[max_lines - 1];
    for (size_t i = max_lines; i < lines.size(); ++i) rest += " " + lines[i];
    lines.resize(max_lines);
    lines.back() = Shorten(rest, size, max_width);
  }
  return lines;
}

double SvgCanvas::WrappedText(double x, double y, std::string_view text, double max_width,
                              const TextStyle& style, double line_height, int max_lines) {
  const double size = style.size > 0 ? style.size : font_size_;
  if (!(line_height > 0)) line_height = 1.3 * size;
  for (const std::string& line : WrapText(text, size, max_width, max_lines)) {
    Text(x, y, line, style);
    y += line_height;
  }
  return y;
}

std::pair<double, double> LabelPlacer::Place(double x, double y, std::string_view text,
                                             double size) {
  const double w = TextWidth(text, size), h = (kAscent + kDescent) * size;
  // Box offsets (left, top) relative to the point: right, left, above, below, then the diagonals.
  const std::array<std::pair<double, double>, 8> directions = {
      {{1, -0.5}, {-1, -0.5}, {-0.5, -1}, {-0.5, 1}, {1, -1}, {-1, -1}, {1, 1}, {-1, 1}}};
  std::pair<double, double> first{}, chosen{};
  bool found = false, have_first = false;
  for (double gap = 4; gap <= 40 && !found; gap += 6) {
    for (const auto& [dx, dy] : directions) {
      const double left = dx > 0 ? x + gap : dx < -0.75 ? x - gap - w : x - w / 2;
      const double top = dy > 0 ? y + gap : dy < -0.75 ? y - gap - h : y - h / 2;
      const TextBox box{left, top, left + w, top + h};
      const std::pair<double, double> baseline{left, top + kAscent * size};
      if (!have_first && Inside(box, bounds_)) first = baseline, have_first = true;
      if (!Inside(box, bounds_) || std::any_of(placed_.begin(), placed_.end(),
                                               [&](const TextBox& b) { return Overlap(box, b); }))
        continue;
      chosen = baseline, found = true;
      break;
    }
  }
  if (!found) chosen = have_first ? first : std::pair<double, double>{x + 4, y - 4};
  placed_.push_back(TextBoxOf(chosen.first, chosen.second, text, size, TextAnchor::kStart));
  return chosen;
}

}  // namespace tactforce::io
