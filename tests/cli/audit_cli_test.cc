// `tactforce simulate sensor` + `tactforce audit`, end to end, as a user runs
// them: a delay is hidden in the simulated data; the audit must name it.
#include <gtest/gtest.h>

#include "support/cli_fixture.h"

namespace tactforce::testing {
namespace {

TEST_F(CliTest, AuditFindsAHiddenDelayInSimulatedData) {
  const auto model = Write("model.json", R"({
  "format": "tactforce.sensor_model.v1",
  "units": "counts", "gain": -40, "offset": 1000, "noise": 0.02, "delay": 0.05
})");
  const std::string sim = (dir() / "sim").string();
  const CliRun run =
      Tactforce({"simulate", "sensor", "--model", model.string(), "--profile", "press-release",
                 "--seconds", "20", "--rate", "200", "--seed", "4", "--out", sim});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string out = (dir() / "report").string();
  const CliRun audit =
      Tactforce({"audit", "--csv", sim + "/run.csv", "--out", out, "--units", "counts"});
  ASSERT_EQ(audit.exit_code, 0) << audit.err;
  const std::string report = ReadFile(out + "/report.json");
  EXPECT_NE(report.find("\"nominal_adequate\": false"), std::string::npos) << report.substr(0, 400);
  // The strongest cause is listed first.
  const size_t causes = report.find("\"causes\"");
  ASSERT_NE(causes, std::string::npos);
  EXPECT_EQ(report.find("\"effect\": \"delay\"", causes), report.find("\"effect\"", causes));
  EXPECT_TRUE(std::filesystem::exists(out + "/extended_model.json"));
  EXPECT_TRUE(std::filesystem::exists(out + "/reading_vs_reference.svg"));
  EXPECT_NE(audit.out.find("delay"), std::string::npos);  // the printed summary
}

TEST_F(CliTest, AuditBadInputNamesTheProblem) {
  const auto few = Write("few.csv", "t,reference,reading\n0,1,2\n0.1,2,3\n");
  const CliRun run = Tactforce({"audit", "--csv", few.string(), "--out", (dir() / "r").string()});
  ExpectBadInput(run);
  EXPECT_NE(run.err.find("too few samples"), std::string::npos) << run.err;
  const auto missing = Write("missing.csv", "t,reference\n0,1\n");
  const CliRun m = Tactforce({"audit", "--csv", missing.string(), "--out", (dir() / "r").string()});
  ExpectBadInput(m);
  EXPECT_NE(m.err.find("missing column(s) reading"), std::string::npos) << m.err;
}

// A per-taxel CSV (issue 26): a missing taxel column is named, exit 2,
// nothing written; with --taxels the expected count is enforced.
TEST_F(CliTest, AuditPerTaxelCsvNamesAMissingColumn) {
  std::string csv = "t,reference,taxel_0,taxel_2\n";
  for (int i = 0; i < 60; ++i)
    csv += std::to_string(0.01 * i) + "," + std::to_string(i % 7) + ",1,2\n";
  const auto gap = Write("gap.csv", csv);
  const std::string out = (dir() / "taxel_report").string();
  const CliRun run = Tactforce({"audit", "--csv", gap.string(), "--out", out});
  ExpectBadInput(run);
  EXPECT_NE(run.err.find("missing column(s) taxel_1"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(out + "/report.json"));
  const CliRun more = Tactforce({"audit", "--csv", gap.string(), "--taxels", "4", "--out", out});
  ExpectBadInput(more);
  EXPECT_NE(more.err.find("taxel_1, taxel_3"), std::string::npos) << more.err;
}

// `audit --out` as `simulate --out`: an earlier report's folder is refused
// (exit 2, nothing written or removed) unless --force, which replaces only
// the report's own files.
TEST_F(CliTest, AuditOutRefusesAFolderWithFilesUnlessForce) {
  const std::string examples = SourceDir().string() + "/client/examples/";
  const std::vector<std::string> audit = {
      "audit",   "--reference", examples + "reference.csv", "--reading", examples + "reading.csv",
      "--quiet", "--out"};
  const std::string out = (dir() / "report").string();
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = audit;
    args.insert(args.end(), extra.begin(), extra.end());
    return Tactforce(args);
  };
  const CliRun first = with({out});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  WriteFile(out + "/summary.txt", "an earlier report");
  WriteFile(out + "/notes.md", "the user's own file");

  const CliRun again = with({out});
  ExpectBadInput(again);
  EXPECT_NE(again.err.find("--out: '" + out + "' is not empty"), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("or --force to replace this audit's files"), std::string::npos)
      << again.err;
  EXPECT_EQ(ReadFile(out + "/summary.txt"), "an earlier report");  // nothing written

  // The same wording as simulate's refusal, but for its own files.
  const CliRun sim = Tactforce({"simulate", "sensor", "--seconds", "2", "--out", out});
  ExpectBadInput(sim);
  EXPECT_NE(sim.err.find("--out: '" + out + "' is not empty"), std::string::npos) << sim.err;
  EXPECT_NE(sim.err.find("or --force to replace this simulation's files"), std::string::npos)
      << sim.err;

  const CliRun forced = with({out, "--force"});
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_NE(ReadFile(out + "/summary.txt"), "an earlier report");
  EXPECT_EQ(ReadFile(out + "/notes.md"), "the user's own file");  // not the audit's: kept
  EXPECT_TRUE(std::filesystem::exists(out + "/report.json"));
  // A file where the folder should be is refused, --force or not.
  WriteFile((dir() / "file").string(), "x");
  ExpectBadInput(with({(dir() / "file").string(), "--force"}));
}

}  // namespace
}  // namespace tactforce::testing
