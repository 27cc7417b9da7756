// io/svg.h: the one tick algorithm (nice steps that cover the range), tick
// labels, escaping, ranges, the colour ramp, and documents built from the
// canvas and the plot elements (RenderSvg included).
#include "tactforce/io/svg.h"

#include <cmath>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "gtest/gtest.h"

namespace tactforce::io {
namespace {

int Count(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

// 1, 2 or 5 times a power of ten.
bool IsNice(double step) {
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (std::abs(mantissa - m) < 1e-9 * m) return true;
  return false;
}

TEST(SvgTicks, NiceStepIsTheSmallestOneTwoFiveAtLeastTheRawStep) {
  EXPECT_EQ(NiceStep(0.3), 0.5);
  EXPECT_EQ(NiceStep(0.2), 0.2);
  EXPECT_EQ(NiceStep(1), 1);
  EXPECT_EQ(NiceStep(1.01), 2);
  EXPECT_EQ(NiceStep(2.2), 5);
  EXPECT_EQ(NiceStep(7), 10);
  EXPECT_EQ(NiceStep(38.3), 50);
  EXPECT_EQ(NiceStep(1600), 2000);
  EXPECT_DOUBLE_EQ(NiceStep(3e-7), 5e-7);
  for (double bad : {0.0, -1.0, double(NAN), double(INFINITY)}) EXPECT_EQ(NiceStep(bad), 1) << bad;
}

TEST(SvgTicks, NiceTicksCoverTheRangeEvenlyAtNiceValues) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> exponent(-6, 6), unit(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const double scale = std::pow(10.0, exponent(rng));
    double lo = unit(rng) * scale, hi = unit(rng) * scale;
    if (lo > hi) std::swap(lo, hi);
    if (!(hi - lo > 1e-12 * scale)) continue;
    for (int intervals : {4, 5, 10}) {
      const Ticks t = NiceTicks(lo, hi, intervals);
      ASSERT_TRUE(IsNice(t.step)) << t.step;
      // The step is less than 2.5 x (hi - lo) / intervals.
      ASSERT_GE(t.values.size(), static_cast<size_t>(intervals / 2.5)) << lo << " " << hi;
      ASSERT_LE(t.values.size(), static_cast<size_t>(intervals) + 1) << lo << " " << hi;
      const double slack = 1e-9 * (hi - lo);
      EXPECT_GE(t.values.front(), lo - slack);
      EXPECT_LE(t.values.back(), hi + slack);
      // Covering: no gap of a whole step at either end.
      EXPECT_LT(t.values.front() - lo, t.step + slack);
      EXPECT_LT(hi - t.values.back(), t.step + slack);
      for (size_t i = 0; i < t.values.size(); ++i) {
        EXPECT_NEAR(t.values[i] / t.step, std::round(t.values[i] / t.step),
                    1e-9);  // multiples of the step
        if (i > 0) {
          EXPECT_NEAR(t.values[i] - t.values[i - 1], t.step, 1e-9 * t.step);
        }
      }
    }
  }
}

TEST(SvgTicks, TicksAreExactMultiplesWithoutNegativeZero) {
  const Ticks t = TicksAt(-1, 1, 0.5);
  ASSERT_EQ(t.values, (std::vector<double>{-1, -0.5, 0, 0.5, 1}));
  EXPECT_FALSE(std::signbit(t.values[2]));
  // The ends are kept despite rounding in the range (0.1 + 0.2 > 0.3).
  EXPECT_EQ(TicksAt(0, 0.1 + 0.2, 0.1).values.size(), 4u);
  EXPECT_EQ(TicksAt(0, 0.3, 0.1).values.back(), 3 * 0.1);
  EXPECT_TRUE(TicksAt(2, 1, 0.5).values.empty());
  EXPECT_TRUE(TicksAt(0, NAN, 0.5).values.empty());
}

TEST(SvgTicks, LabelsCarryNoRoundingNoise) {
  EXPECT_EQ(TickLabel(0.1 + 0.2, 0.1), "0.3");
  EXPECT_EQ(TickLabel(-1e-17, 0.1), "0");
  EXPECT_EQ(TickLabel(-0.0, 1), "0");
  EXPECT_EQ(TickLabel(2000, 2000), "2000");
  EXPECT_EQ(TickLabel(-100, 50), "-100");
  EXPECT_EQ(TickLabel(1e6, 5e5), "1e+06");
  EXPECT_EQ(TickLabel(0.00025, 0.00005), "0.00025");
}

TEST(SvgText, EscapeCoversMarkupAndQuotes) {
  EXPECT_EQ(SvgEscape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
  EXPECT_EQ(SvgEscape("plain kg/m\xc2\xb3"), "plain kg/m\xc2\xb3");
  SvgCanvas canvas(100, 50);
  canvas.Text(1, 2, "<b>&", {.bold = true});
  canvas.Rect(0, 0, 10, 10, "none", nullptr, "x\"y");
  const std::string svg = canvas.Finish();
  EXPECT_NE(svg.find(">&lt;b&gt;&amp;</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("class=\"x&quot;y\""), std::string::npos) << svg;
  EXPECT_EQ(svg.find("<b>"), std::string::npos);
}

TEST(SvgRange, AxisRangesForEmptyFlatAndPaddedData) {
  Range empty;
  empty.Include(NAN);
  EXPECT_EQ(empty.ForAxis().lo, 0);
  EXPECT_EQ(empty.ForAxis().hi, 1);
  Range flat;
  flat.Include({3.0, 3.0, INFINITY});
  EXPECT_EQ(flat.ForAxis().lo, 3);
  EXPECT_EQ(flat.ForAxis().hi, 4);
  Range data;
  data.Include({-1.0, 1.0});
  EXPECT_DOUBLE_EQ(data.ForAxis(0.05).lo, -1.1);
  EXPECT_DOUBLE_EQ(data.ForAxis(0.05).hi, 1.1);
}

TEST(SvgColor, RampEndsAndMiddle) {
  const ColorRamp ramp = ColorRamp::Viridis();
  EXPECT_EQ(HexColor(ramp.At(0)), "#440154");
  EXPECT_EQ(HexColor(ramp.At(1)), "#fde725");
  EXPECT_EQ(HexColor(ramp.At(0.5)), "#21918c");
  EXPECT_EQ(ramp.At(-3), ramp.At(0));
  EXPECT_EQ(ramp.At(7), ramp.At(1));
  EXPECT_EQ(ramp.At(NAN), ramp.At(0));
  EXPECT_EQ(HexColor(ColorRamp({0x000000, 0xffffff}).At(0.5)), "#808080");
}

// Tick labels of a document: the texts of <text> elements that are numbers.
std::vector<std::string> NumberTexts(const std::string& svg) {
  std::vector<std::string> out;
  static const std::regex re(">(-?[0-9.]+(e[-+][0-9]+)?)</text>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), re); it != std::sregex_iterator();
       ++it)
    out.push_back((*it)[1]);
  return out;
}

TEST(SvgPlot, AxesLabelTheTicksInsideTheFrameOnly) {
  SvgCanvas canvas(400, 300);
  const PlotFrame frame{60, 20, 300, 200, 0, 10, -1, 1};
  DrawAxes(canvas, frame, TicksAt(-5, 15, 5), {.title = "time [s]"}, NiceTicks(-1, 1, 4),
           {.title = "force <N>"});
  const std::string svg = canvas.Finish();
  EXPECT_EQ(NumberTexts(svg),
            (std::vector<std::string>{"0", "5", "10", "-1", "-0.5", "0", "0.5", "1"}));
  EXPECT_NE(svg.find(">time [s]</text>"), std::string::npos);
  EXPECT_NE(svg.find("rotate(-90"), std::string::npos) << "the y title is vertical";
  EXPECT_NE(svg.find(">force &lt;N&gt;</text>"), std::string::npos);
}

TEST(SvgPlot, TracesBreakAtMissingPointsAndLegendsNameThem) {
  SvgCanvas canvas(400, 300);
  const PlotFrame frame{0, 0, 100, 100, 0, 4, 0, 1};
  DrawLineTrace(canvas, frame, {0, 1, 2, 3, 4}, {0, 1, NAN, 1, 0}, Stroke{"red", 2, "4,2"});
  DrawLegend(canvas, 10, 10, {{.label = "a & b", .line = Stroke{"red", 2, ""}}});
  const std::string svg = canvas.Finish();
  EXPECT_NE(svg.find("d=\"M0.0,100.0L25.0,0.0M75.0,0.0L100.0,100.0\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("stroke-dasharray=\"4,2\""), std::string::npos);
  EXPECT_NE(svg.find(">a &amp; b</text>"), std::string::npos);
}

TEST(SvgPlot, MarkersColourBarAndGroups) {
  SvgCanvas canvas(300, 300);
  canvas.OpenGroup("id=\"outer\"");
  DrawMarker(canvas, 50, 50,
             {.shape = MarkerShape::kRing,
              .color = "#e4007c",
              .size = 12,
              .halo = true,
              .css_class = "ring"});
  ColorBar bar{.x = 200,
               .y = 40,
               .height = 200,
               .lo = 0,
               .hi = 8000,
               .ticks = TicksAt(0, 8000, 2000),
               .title = "density (kg/m\xc2\xb3)",
               .marks = {{7800, "steel <x>"}, {9000, "off the bar"}}};
  DrawColorBar(canvas, bar, ColorRamp::Viridis());
  const std::string svg = canvas.Finish();  // closes "outer"
  EXPECT_EQ(Count(svg, "<g"), Count(svg, "</g>"));
  EXPECT_EQ(Count(svg, "class=\"ring\""), 1);
  EXPECT_EQ(Count(svg, "<circle"), 2) << "halo and ring";
  EXPECT_EQ(NumberTexts(svg), (std::vector<std::string>{"0", "2000", "4000", "6000", "8000"}));
  EXPECT_NE(svg.find("<title>steel &lt;x&gt;</title>"), std::string::npos);
  EXPECT_EQ(svg.find("off the bar"), std::string::npos);
  EXPECT_NE(svg.find("url(#colour-bar-ramp)"), std::string::npos);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
}

TEST(SvgShapes, EllipseTurnsAboutItsCentreAndDegeneratesToALine) {
  SvgCanvas canvas(200, 200);
  const Stroke blue{"#00f", 1.5, ""};
  canvas.Ellipse(50, 60, 20, 5, 30, "none", &blue);
  canvas.Ellipse(100, 100, 10, 4, 0, "#ccc");
  canvas.Ellipse(100, 100, 10, 0, 90, "none", &blue);  // a vertical segment of length 20
  const std::string svg = canvas.Finish();
  EXPECT_NE(svg.find("<ellipse cx=\"50.0\" cy=\"60.0\" rx=\"20.00\" ry=\"5.00\" "
                     "transform=\"rotate(30.00 50.0 60.0)\" "
                     "fill=\"none\" stroke=\"#00f\" stroke-width=\"1.5\"/>"),
            std::string::npos)
      << svg;
  EXPECT_NE(svg.find("<ellipse cx=\"100.0\" cy=\"100.0\" rx=\"10.00\" ry=\"4.00\" fill=\"#ccc\"/>"),
            std::string::npos);
  EXPECT_EQ(Count(svg, "<ellipse"), 2);
  EXPECT_NE(svg.find("<line x1=\"100.0\" y1=\"90.0\" x2=\"100.0\" y2=\"110.0\""), std::string::npos)
      << svg;
}

TEST(SvgShapes, PolygonIsOneClosedPath) {
  SvgCanvas canvas(100, 100);
  canvas.Polygon({{0, 0}, {10, 0}, {10, 10}}, {"red", 1, ""}, "#fee");
  canvas.Polygon({}, {"red", 1, ""});
  const std::string svg = canvas.Finish();
  EXPECT_EQ(Count(svg, "<path"), 1);
  EXPECT_NE(svg.find("<path d=\"M0.0,0.0L10.0,0.0L10.0,10.0Z\" fill=\"#fee\" stroke=\"red\"/>"),
            std::string::npos)
      << svg;
}

TEST(SvgShapes, ArrowHasAShaftAndAHeadAtItsTip) {
  SvgCanvas canvas(200, 200);
  DrawArrow(canvas, 10, 50, 110, 50, {"#c00", 2, ""}, 10);
  const std::string svg = canvas.Finish();
  // Shaft up to the head's base, head tip at the arrow's end.
  EXPECT_NE(svg.find("<line x1=\"10.0\" y1=\"50.0\" x2=\"100.0\" y2=\"50.0\" stroke=\"#c00\" "
                     "stroke-width=\"2\"/>"),
            std::string::npos)
      << svg;
  EXPECT_NE(
      svg.find("<path d=\"M110.0,50.0L100.0,54.5L100.0,45.5Z\" fill=\"#c00\" stroke=\"#c00\"/>"),
      std::string::npos)
      << svg;
  // A short arrow gets a proportionally short head; a zero arrow is a dot.
  SvgCanvas small(100, 100);
  DrawArrow(small, 0, 0, 0, 5, {"black", 1, ""}, 10);
  DrawArrow(small, 20, 20, 20, 20, {"black", 1, ""});
  const std::string s = small.Finish();
  EXPECT_NE(s.find("<line x1=\"0.0\" y1=\"0.0\" x2=\"0.0\" y2=\"2.0\""), std::string::npos) << s;
  EXPECT_EQ(Count(s, "<circle cx=\"20.0\" cy=\"20.0\""), 1) << s;
}

TEST(SvgPlot, RenderSvgStacksPanelsOverOneTimeAxis) {
  SvgPlot plot;
  plot.title = "grasp <sphere>";
  plot.x_label = "t [s]";
  for (int i = 0; i <= 40; ++i) plot.x.push_back(0.1 * i);
  SvgPanel forces{.title = "forces", .y_label = "N"};
  forces.series.push_back(
      {.name = "desired", .color = "#000", .dashed = true, .y = std::vector<double>(41, 2.0)});
  SvgPanel slip{.title = "slip", .y_label = "mm"};
  slip.series.push_back({.name = "slip", .color = "#c00", .y = plot.x});
  slip.series.back().y[20] = NAN;
  plot.panels = {forces, slip};
  plot.markers = {{1.0, "lift"}, {9.0, "outside"}};
  const std::string svg = RenderSvg(plot, 900, 200);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("height=\"539\""), std::string::npos) << "54 + 2 x 200 + 40 + 45";
  EXPECT_NE(svg.find(">grasp &lt;sphere&gt;</text>"), std::string::npos);
  EXPECT_NE(svg.find(">desired</text>"), std::string::npos);
  EXPECT_EQ(Count(svg, ">lift</text>"), 1) << "the marker's label on the first panel only";
  EXPECT_EQ(svg.find("outside"), std::string::npos);
  EXPECT_EQ(Count(svg, ">t [s]</text>"), 1) << "x title under the last panel only";
  for (const char* tick : {">0.5</text>", ">4</text>"})
    EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  // The slip trace breaks at its missing point: two pieces.
  const std::regex slip_path("<path d=\"(M[^\"]*)\" fill=\"none\" stroke=\"#c00\"");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, slip_path));
  EXPECT_EQ(Count(m[1], "M"), 2);
}

// ---- Text layout ------------------------------------------------------------------

TEST(SvgText, AxisTicksGiveAtLeastThreeTicksOnAnyRange) {
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> exponent(-6, 6), unit(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const double scale = std::pow(10.0, exponent(rng));
    double lo = unit(rng) * scale, hi = unit(rng) * scale;
    if (lo > hi) std::swap(lo, hi);
    if (!(hi - lo > 1e-9 * scale)) continue;
    for (int intervals : {2, 4, 5, 10}) {
      const Ticks t = AxisTicks(lo, hi, intervals);
      ASSERT_GE(t.values.size(), 3u) << lo << " " << hi << " " << intervals;
      ASSERT_LE(t.values.size(), static_cast<size_t>(std::max(intervals, 5)) + 2)
          << lo << " " << hi;
      ASSERT_TRUE(IsNice(t.step)) << t.step;
    }
  }
}

TEST(SvgText, WrapTextKeepsEveryLineWithinTheWidth) {
  std::mt19937 rng(26);
  std::uniform_int_distribution<int> word_length(1, 14), words(1, 40), letter('a', 'z');
  std::uniform_real_distribution<double> width(40, 600);
  for (int trial = 0; trial < 300; ++trial) {
    std::string text;
    for (int w = words(rng); w > 0; --w) {
      for (int c = word_length(rng); c > 0; --c) text.push_back(static_cast<char>(letter(rng)));
      if (w > 1) text.push_back(' ');
    }
    const double max_width = width(rng);
    const std::vector<std::string> lines = WrapText(text, 12, max_width, 3);
    ASSERT_GE(lines.size(), 1u);
    ASSERT_LE(lines.size(), 3u);
    for (const std::string& line : lines) EXPECT_LE(TextWidth(line, 12), max_width + 1e-9) << line;
    if (TextWidth(text, 12) <= max_width)
      EXPECT_EQ(lines, std::vector<std::string>{text}) << "fits: one line";
  }
}

TEST(SvgText, LabelPlacerSeparatesLabelsAtOnePoint) {
  std::mt19937 rng(27);
  std::uniform_real_distribution<double> where(80, 220);
  for (int trial = 0; trial < 100; ++trial) {
    LabelPlacer placer({0, 0, 300, 300});
    const double x = where(rng), y = where(rng);
    std::vector<TextBox> boxes;
    for (const char* name :
         {"thumb", "index", "middle"}) {  // all at the same point, as a pinch seen along its axis
      const auto [lx, ly] = placer.Place(x, y, name, 11);
      boxes.push_back(TextBoxOf(lx, ly, name, 11, TextAnchor::kStart));
      EXPECT_LT(std::hypot(boxes.back().left - x, ly - y), 80) << "near its point";
    }
    for (size_t i = 0; i < boxes.size(); ++i)
      for (size_t j = i + 1; j < boxes.size(); ++j)
        EXPECT_FALSE(Overlap(boxes[i], boxes[j])) << i << " " << j;
  }
}

TEST(SvgText, TextBoxesFollowAnchorAndRotation) {
  const TextBox start = TextBoxOf(100, 50, "abcde", 10, TextAnchor::kStart);
  EXPECT_DOUBLE_EQ(start.left, 100);
  EXPECT_DOUBLE_EQ(start.right, 130);
  const TextBox end = TextBoxOf(100, 50, "abcde", 10, TextAnchor::kEnd);
  EXPECT_DOUBLE_EQ(end.right, 100);
  const TextBox vertical = TextBoxOf(100, 50, "abcde", 10, TextAnchor::kMiddle, true);
  EXPECT_DOUBLE_EQ(vertical.bottom - vertical.top, 30)
      << "read bottom to top: as tall as the text is long";
  EXPECT_DOUBLE_EQ(TextWidth("\xc2\xb5s", 10), 12) << "code points, not bytes";
}

}  // namespace
}  // namespace tactforce::io
