// `tactforce plan --plot FILE`: the built binary draws the shipped example
// plan and trajectory, and an unwritable --plot is a usage error naming it.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_fixture.h"

namespace tactforce {
namespace {

namespace fs = std::filesystem;
using testing::CliRun;
using ::testing::HasSubstr;
using testing::ReadFile;

int CountOf(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

class PlotCliTest : public testing::CliTest {
 protected:
  static std::string Example(const char* name) {
    return (fs::path(testing::SourceDir()) / "client" / "examples" / name).string();
  }
  void SetUp() override {
    testing::CliTest::SetUp();
    fs::create_directory(plots());
  }
  fs::path plots() const { return dir() / "plots"; }
  // The files in plots() (the plot and nothing left over from writing it).
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const fs::directory_entry& e : fs::directory_iterator(plots()))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

TEST_F(PlotCliTest, PlanPlotsTheShippedExample) {
  const std::string plot = (plots() / "plan.svg").string();
  const CliRun run =
      Tactforce({"plan", "--local", "--request", Example("sphere_pinch.json"), "--plot", plot});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");
  EXPECT_THAT(run.out, HasSubstr("OPTIMAL")) << "the plan is still printed";
  EXPECT_EQ(Files(), std::vector<std::string>{"plan.svg"});
  const std::string svg = ReadFile(plot);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
  EXPECT_EQ(CountOf(svg, "class=\"view\""), 3);
  for (const char* glyph : {"class=\"force-arrow\"", "class=\"cone\"", "class=\"spread-ellipse\""})
    EXPECT_EQ(CountOf(svg, glyph), 2 * 3) << glyph;
  EXPECT_EQ(CountOf(svg, "class=\"com\""), 3);
  EXPECT_EQ(CountOf(svg, "class=\"gravity\""), 3);
  EXPECT_THAT(svg, HasSubstr("id=\"legend\""));
  EXPECT_THAT(svg, HasSubstr("N per m"));
  EXPECT_THAT(svg, HasSubstr("Plan: OPTIMAL"));
  EXPECT_THAT(svg, HasSubstr("12-facet pyramids"));
}

TEST_F(PlotCliTest, TrajectoryPlotHasAPanelPerStep) {
  const std::string plot = (plots() / "trajectory.svg").string();
  const CliRun run = Tactforce(
      {"plan", "--local", "--trajectory", Example("wrench_lift_trajectory.json"), "--plot", plot});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string svg = ReadFile(plot);
  EXPECT_EQ(CountOf(svg, "class=\"step-panel\""), 4);
  EXPECT_EQ(CountOf(svg, "class=\"view\""), 4 * 3);
  EXPECT_EQ(CountOf(svg, "class=\"force-arrow\""), 4 * 3 * 3);
}

TEST_F(PlotCliTest, UnwritablePlotIsAUsageErrorNamingTheFlag) {
  for (const std::string& plot : {(plots() / "missing" / "plan.svg").string(), plots().string()}) {
    const CliRun run =
        Tactforce({"plan", "--local", "--request", Example("sphere_pinch.json"), "--plot", plot});
    ExpectBadInput(run);
    EXPECT_THAT(run.err, HasSubstr("--plot")) << plot;
    EXPECT_THAT(run.err, HasSubstr(plot));
  }
  EXPECT_TRUE(Files().empty());
}

// Pictures are SVG: a .png (or any non-.svg) name is refused before any work
// by every command with --plot, instead of SVG bytes in a .png file.
TEST_F(PlotCliTest, NonSvgPlotNamesAreRefusedByEveryCommand) {
  const std::string png = (plots() / "picture.png").string();
  const std::vector<std::vector<std::string>> commands = {
      {"plan", "--local", "--request", Example("sphere_pinch.json"), "--plot", png},
      {"plan", "--local", "--trajectory", Example("wrench_lift_trajectory.json"), "--plot", png},
      {"inertia", "--csv", Example("inertia_log.csv"), "--mesh", Example("inertia_box.stl"),
       "--method", "density", "--plot", png},
      {"load", "--target", "127.0.0.1:1", "--rpc", "plan", "-n", "1", "--plot", png},
  };
  for (const std::vector<std::string>& args : commands) {
    const CliRun run = Tactforce(args);
    SCOPED_TRACE(args[0]);
    ExpectBadInput(run);
    EXPECT_THAT(run.err, HasSubstr("--plot: '" + png + "': pictures are SVG"));
  }
  EXPECT_TRUE(Files().empty());
}

TEST_F(PlotCliTest, HelpDescribesThePlot) {
  const CliRun run = Tactforce({"plan", "--help"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_THAT(run.out, HasSubstr("--plot"));
  EXPECT_THAT(run.out, HasSubstr("small multiples"));
}

}  // namespace
}  // namespace tactforce
