// Provenance (app/provenance.h, app/output_guard.h) in the outputs of the commands, and the
// refusal to overwrite results of other inputs without --force.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "core/io/file_util.h"
#include "core/io/sha256.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing_fixtures::RunTriadcal;

std::string Scenario(int seed) {
  return "seed: " + std::to_string(seed) +
         "\nprofile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, "
         "rate_hz: 100}\n"
         "noise: {accel_mV: 1, angle_arcsec: 15}\n"
         "run: {sensor: {serial: \"SN 0042\", model: ADXL325}}\n";
}

class ProvenanceTest : public testing_fixtures::TempDirTest {
 protected:
  testing_fixtures::CommandResult Triadcal(const std::string& args) {
    return RunTriadcal(args, Path("err.txt"));
  }
  json Json(const std::string& name) { return json::parse(ReadFile(Path(name))); }
  std::string Abs(const std::string& name) { return fs::absolute(Path(name)).lexically_normal(); }
};

TEST_F(ProvenanceTest, SimulateAndFitRecordTheirInputs) {
  WriteText("a.yaml", Scenario(1));
  ASSERT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("a")).status, 0);
  const json tp = Json("a/truth.json")["provenance"];
  EXPECT_EQ(tp["tool"], "triadcal");
  EXPECT_EQ(tp["version"], TRIADCAL_VERSION);  // project()'s, from tests/CMakeLists.txt
  EXPECT_FALSE(tp["git_commit"].get<std::string>().empty());
  EXPECT_TRUE(std::regex_match(tp["date_utc"].get<std::string>(),
                               std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  EXPECT_EQ(tp["command_line"], "triadcal simulate " + Path("a.yaml") + " -o " + Path("a"));
  ASSERT_EQ(tp["inputs"].size(), 1u);
  EXPECT_EQ(tp["inputs"][0]["role"], "scenario");
  EXPECT_EQ(tp["inputs"][0]["path"], Abs("a.yaml"));
  EXPECT_EQ(tp["inputs"][0]["sha256"], Sha256OfFile(Path("a.yaml")));

  ASSERT_EQ(Triadcal("fit " + Path("a/run.yaml") + " -o " + Path("fit.json")).status, 0);
  const json fp = Json("fit.json")["provenance"];
  ASSERT_EQ(fp["inputs"].size(), 2u);
  EXPECT_EQ(fp["inputs"][0]["role"], "run");
  EXPECT_EQ(fp["inputs"][0]["path"], Abs("a/run.yaml"));
  EXPECT_EQ(fp["inputs"][0]["sha256"], Sha256OfFile(Path("a/run.yaml")));
  EXPECT_EQ(fp["inputs"][1]["role"], "data");
  EXPECT_EQ(fp["inputs"][1]["path"], Abs("a/run.csv"));
  EXPECT_EQ(fp["inputs"][1]["sha256"], Sha256OfFile(Path("a/run.csv")));
  EXPECT_EQ(fp["sensor"], json({{"serial", "SN 0042"}, {"model", "ADXL325"}}));

  // apply: the CSV carries it on a comment line.
  ASSERT_EQ(
      Triadcal("apply " + Path("fit.json") + " " + Path("a/run.yaml") + " -o " + Path("w.csv"))
          .status,
      0);
  const std::string csv = ReadFile(Path("w.csv"));
  const std::size_t at = csv.find("# provenance: ");
  ASSERT_NE(at, std::string::npos);
  const json ap = json::parse(csv.substr(at + 14, csv.find('\n', at) - at - 14));
  EXPECT_EQ(ap["inputs"][0]["role"], "calibration");
  EXPECT_EQ(ap["inputs"][0]["sha256"], Sha256OfFile(Path("fit.json")));
}

// The version has one source, project() in CMakeLists.txt: --version, the
// provenance (above) and the HTML report's generator all give it.
TEST_F(ProvenanceTest, VersionIsTheProjectsEverywhere) {
  ASSERT_EQ(std::system((std::string(TRIADCAL_BIN) + " --version > " + Path("version.txt")).c_str()),
            0);
  EXPECT_EQ(ReadFile(Path("version.txt")), std::string("triadcal ") + TRIADCAL_VERSION + "\n");
  WriteText("a.yaml", Scenario(1));
  ASSERT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("a")).status, 0);
  ASSERT_EQ(Triadcal("fit " + Path("a/run.yaml") + " -o " + Path("fit.json")).status, 0);
  ASSERT_EQ(Triadcal("report " + Path("fit.json") + " -o " + Path("fit.html")).status, 0);
  EXPECT_NE(ReadFile(Path("fit.html"))
                .find(std::string("<meta name=\"generator\" content=\"triadcal ") +
                      TRIADCAL_VERSION + "\">"),
            std::string::npos);
}

TEST_F(ProvenanceTest, RefusesToOverwriteResultsOfOtherInputs) {
  WriteText("a.yaml", Scenario(1));
  WriteText("b.yaml", Scenario(2));
  ASSERT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("a")).status, 0);
  ASSERT_EQ(Triadcal("simulate " + Path("b.yaml") + " -o " + Path("b")).status, 0);
  ASSERT_EQ(Triadcal("fit " + Path("a/run.yaml") + " -o " + Path("fit.json")).status, 0);
  // The same inputs again: replaced.
  ASSERT_EQ(Triadcal("fit " + Path("a/run.yaml") + " -o " + Path("fit.json")).status, 0);
  const std::string before = ReadFile(Path("fit.json"));

  auto r = Triadcal("fit " + Path("b/run.yaml") + " -o " + Path("fit.json"));
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("fit.json") +
                       ": holds results of other inputs (data " + Abs("a/run.csv") + ", run " +
                       Abs("a/run.yaml") + "); --force overwrites it\n");
  EXPECT_EQ(ReadFile(Path("fit.json")), before);
  r = Triadcal("fit " + Path("b/run.yaml") + " -o " + Path("fit.json") + " --force");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Json("fit.json")["provenance"]["inputs"][0]["path"], Abs("b/run.yaml"));

  // A file that is not a triadcal output.
  WriteText("notes.json", "{\"mine\": 1}\n");
  r = Triadcal("fit " + Path("a/run.yaml") + " -o " + Path("notes.json"));
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("notes.json") +
                       ": exists and is not a triadcal output (no provenance); --force "
                       "overwrites it\n");
  EXPECT_EQ(ReadFile(Path("notes.json")), "{\"mine\": 1}\n");
}

TEST_F(ProvenanceTest, SimulateRefusesAFolderOfOtherResults) {
  WriteText("a.yaml", Scenario(1));
  WriteText("b.yaml", Scenario(2));
  ASSERT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("out")).status, 0);
  // Again from the same scenario (another seed): allowed.
  ASSERT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("out") + " --seed 5").status, 0);
  const std::string truth = ReadFile(Path("out/truth.json"));
  auto r = Triadcal("simulate " + Path("b.yaml") + " -o " + Path("out"));
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("out") +
                       ": holds results of other inputs (scenario " + Abs("a.yaml") +
                       "); --force writes into it\n");
  EXPECT_EQ(ReadFile(Path("out/truth.json")), truth);
  r = Triadcal("simulate " + Path("b.yaml") + " -o " + Path("out") + " --force");
  EXPECT_EQ(r.status, 0) << r.err;

  // A folder holding other files but no results is fine; one holding an OUT
  // of another command is not.
  fs::create_directories(Path("c"));
  WriteText("c/notes.txt", "bench log\n");
  EXPECT_EQ(Triadcal("simulate " + Path("a.yaml") + " -o " + Path("c")).status, 0);
  fs::create_directories(Path("d"));
  ASSERT_EQ(Triadcal("fit " + Path("out/run.yaml") + " -o " + Path("d/fit.json")).status, 0);
  r = Triadcal("simulate " + Path("a.yaml") + " -o " + Path("d"));
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("d") +
                       ": holds results of another simulation or command; --force writes into "
                       "it\n");
}

}  // namespace
}  // namespace triadcal
