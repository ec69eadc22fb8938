// Issue 15 at the command line: Monte Carlo and batch give the same results
// on one process, on `mpirun -n 2` and as Slurm shards merged; the production
// batch of 20 units with 2 bad files and 1 unit outside its limits; reruns
// lose nothing. Short runs (24 s at 50 Hz) keep this under a minute.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/temp_dir_test.h"
#include "tools/distribution/mpi_context.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

nlohmann::json ReadJson(const fs::path& p) { return nlohmann::json::parse(Slurp(p)); }

const char* kMpirun = "mpirun -n 2 --allow-run-as-root --oversubscribe ";

// mpirun, and a triadcal built with MPI (TRIADCAL_MPI).
bool HaveMpirun() {
  return MpiBuilt() && std::system("command -v mpirun > /dev/null 2>&1") == 0;
}

// The scenario of every unit: the paper's bench, a short run at a low rate.
std::string ScenarioText(int seed, double Kx) {
  return "seed: " + std::to_string(seed) +
         "\n"
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0],\n"
         "          duration_s: 24, rate_hz: 50}\n"
         "truth: {Kx: " +
         std::to_string(Kx) +
         ", dpsi: -33, dlambda2: -33}\n"
         "truth_spread: {dlambda2: 0.5}\n"
         "noise: {accel_mV: 2.0, angle_arcsec: 0}\n"
         "run:\n"
         "  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}\n"
         "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 2.0}\n"
         "  constraints:\n"
         "    - {expr: \"dpsi - dlambda2\", value_arcmin: 0, sigma_arcsec: 30}\n";
}

class ScaleOut : public testing_fixtures::TempDirTest {
 protected:
  std::string bin_ = TRIADCAL_BIN;

  int Run(const std::string& args, const std::string& log = "log.txt") {
    return std::system((bin_ + " " + args + " > " + Path(log) + " 2>&1").c_str());
  }
  int RunMpi(const std::string& args) {
    return std::system((kMpirun + bin_ + " " + args + " > " + Path("mpi.txt") + " 2>&1").c_str());
  }
  // Simulates unit `serial` into DIR/units/serial/.
  void SimulateUnit(const std::string& serial, int seed, double Kx = 171.5) {
    const std::string scen = WriteText("scenario_" + serial + ".yaml", ScenarioText(seed, Kx));
    ASSERT_EQ(Run("simulate " + scen + " -o " + Path("units/" + serial)), 0)
        << Slurp(Path("log.txt"));
  }
  // The single summary_*.json in `dir` whose name contains `part`.
  fs::path Summary(const std::string& dir, const std::string& part = "") {
    fs::path found;
    int n = 0;
    for (const auto& e : fs::directory_iterator(Path(dir))) {
      const std::string name = e.path().filename().string();
      if (name.rfind("summary_", 0) == 0 && e.path().extension() == ".json" &&
          name.find(part) != std::string::npos) {
        found = e.path();
        ++n;
      }
    }
    EXPECT_EQ(n, 1) << dir << " " << part;
    return found;
  }
};

// Execution fields (timing, how the work was split) are the only ones allowed
// to differ between one process, MPI ranks and merged shards.
nlohmann::json WithoutExecution(nlohmann::json j) {
  for (const char* k : {"time_s", "threads", "ranks", "shards", "execution", "output_dir",
                        "provenance"}) {
    j.erase(k);
  }
  if (j.contains("results")) {
    for (nlohmann::json& r : j["results"]) {
      r.erase("time_s");
      r.erase("provenance");
    }
  }
  return j;
}

TEST_F(ScaleOut, MonteCarloShardsMergedEqualTheWhole) {
  const std::string scen = WriteText("mc.yaml", ScenarioText(1, 171.5));
  const std::string common = "montecarlo " + scen + " -n 7 --per-seed";
  ASSERT_EQ(Run(common + " -o " + Path("whole.json")), 0) << Slurp(Path("log.txt"));
  for (int i = 1; i <= 3; ++i) {
    const std::string out = Path("s" + std::to_string(i) + ".json");
    ASSERT_EQ(Run(common + " --shard " + std::to_string(i) + "/3 -o " + out), 0)
        << Slurp(Path("log.txt"));
  }
  // Any order of the shard files.
  ASSERT_EQ(Run("merge " + Path("s3.json") + " " + Path("s1.json") + " " + Path("s2.json") +
                " -o " + Path("merged.json")),
            0)
      << Slurp(Path("log.txt"));
  const nlohmann::json whole = ReadJson(Path("whole.json"));
  const nlohmann::json merged = ReadJson(Path("merged.json"));
  EXPECT_EQ(WithoutExecution(merged), WithoutExecution(whole));
  EXPECT_EQ(merged["shards"], 3);
  // Shard 2 of 3 of 7 seeds: items [2, 4), seeds 3 and 4.
  const nlohmann::json s2 = ReadJson(Path("s2.json"));
  EXPECT_EQ(s2["seeds"], nlohmann::json::array({3, 4}));
  EXPECT_EQ(s2["shard"]["records"].size(), 2u);

  // A shard missing, or given twice: named, exit 2, no output.
  EXPECT_EQ(Run("merge " + Path("s1.json") + " " + Path("s3.json") + " -o " + Path("m2.json"),
                "err.txt") >>
                8,
            2);
  EXPECT_EQ(Slurp(Path("err.txt")), "triadcal: error: " + Path("s1.json") +
                                        ": shard: shard 2/3 is missing from the merge\n");
  EXPECT_EQ(Run("merge " + Path("s1.json") + " " + Path("s1.json") + " " + Path("s2.json") +
                    " -o " + Path("m2.json"),
                "err.txt") >>
                8,
            2);
  EXPECT_EQ(Slurp(Path("err.txt")), "triadcal: error: " + Path("s1.json") +
                                        ": shard: 1/3 given twice (also " + Path("s1.json") +
                                        ")\n");
  EXPECT_FALSE(fs::exists(Path("m2.json")));
  EXPECT_EQ(Run("montecarlo " + scen + " -n 7 --shard 4/3 -o " + Path("m3.json"), "err.txt") >> 8,
            2);
  EXPECT_EQ(Slurp(Path("err.txt")),
            "triadcal: error: --shard: expected I/N with 1 <= I <= N, got '4/3'\n");
}

TEST_F(ScaleOut, MonteCarloOnTwoMpiRanksEqualsOneProcess) {
  if (!HaveMpirun()) GTEST_SKIP() << "mpirun not installed (Debian: openmpi-bin) or built without MPI";
  const std::string scen = WriteText("mc.yaml", ScenarioText(1, 171.5));
  const std::string common = "montecarlo " + scen + " -n 6 --per-seed";
  ASSERT_EQ(Run(common + " -o " + Path("one.json")), 0) << Slurp(Path("log.txt"));
  ASSERT_EQ(RunMpi(common + " -o " + Path("two.json")), 0) << Slurp(Path("mpi.txt"));
  const nlohmann::json two = ReadJson(Path("two.json"));
  EXPECT_EQ(two["ranks"], 2);
  EXPECT_EQ(WithoutExecution(two), WithoutExecution(ReadJson(Path("one.json"))));
  // Only rank 0 prints: one table, one "wrote".
  const std::string out = Slurp(Path("mpi.txt"));
  EXPECT_EQ(out.find("wrote"), out.rfind("wrote")) << out;
  // A shard of an MPI job is the same shard.
  ASSERT_EQ(RunMpi(common + " --shard 2/2 -o " + Path("two_s2.json")), 0);
  ASSERT_EQ(Run(common + " --shard 1/2 -o " + Path("one_s1.json")), 0);
  ASSERT_EQ(Run("merge " + Path("one_s1.json") + " " + Path("two_s2.json") + " -o " +
                Path("merged.json")),
            0);
  EXPECT_EQ(WithoutExecution(ReadJson(Path("merged.json"))),
            WithoutExecution(ReadJson(Path("one.json"))));
}

// The acceptance batch: 20 units, 2 bad files, 1 outside its limits.
TEST_F(ScaleOut, BatchOfTwentyUnitsNamesTheThreeFailuresAndRerunsLoseNothing) {
  std::string manifest =
      "limits: {Kx: {min: 165, max: 178}, W0x: {sigma_max: 5}}\n"
      "runs:\n";
  for (int i = 1; i <= 20; ++i) {
    char serial[16];
    std::snprintf(serial, sizeof serial, "SN%03d", i);
    // SN007's scale factor is off the line's limits; SN013 and SN017 are bad files.
    SimulateUnit(serial, 100 + i, i == 7 ? 181.0 : 171.5);
    manifest += std::string("  - {serial: ") + serial + ", run: units/" + serial + "/run.yaml}\n";
  }
  // A run.yaml that is not YAML, and a CSV with a bad cell.
  WriteText("units/SN013/run.yaml", "data: run.csv\nbench: [\n");
  {
    std::string csv = Slurp(Path("units/SN017/run.csv"));
    const std::size_t header = csv.find("\nt,");
    const std::size_t row = csv.find('\n', header + 1) + 1;
    csv.replace(csv.find(',', row), 1, "x,");
    WriteText("units/SN017/run.csv", csv);
  }
  const std::string man = WriteText("manifest.yaml", manifest);
  ASSERT_EQ(Run("batch " + man + " -o " + Path("cal")), 0) << Slurp(Path("log.txt"));
  const nlohmann::json s = ReadJson(Summary("cal"));
  EXPECT_EQ(s["units"], 20);
  EXPECT_EQ(s["pass"], 17);
  EXPECT_EQ(s["fail"], 1);
  EXPECT_EQ(s["error"], 2);
  std::map<std::string, nlohmann::json> by_serial;
  for (const nlohmann::json& r : s["results"]) by_serial[r["serial"]] = r;
  // The bad files: the very line `triadcal fit` gives on stderr.
  for (const char* bad : {"SN013", "SN017"}) {
    const std::string run = Path(std::string("units/") + bad + "/run.yaml");
    EXPECT_EQ(Run("fit " + run + " -o " + Path("x.json"), "fit_err.txt") >> 8, 2);
    EXPECT_EQ(by_serial[bad]["status"], "error");
    EXPECT_EQ("triadcal: error: " + by_serial[bad]["reason"].get<std::string>() + "\n",
              Slurp(Path("fit_err.txt")))
        << bad;
    EXPECT_EQ(by_serial[bad]["folder"], "");
  }
  // The unit outside its limits: which parameter, its value, the limit, the unit.
  const nlohmann::json& f = by_serial["SN007"];
  EXPECT_EQ(f["status"], "fail");
  ASSERT_EQ(f["violations"].size(), 1u);
  EXPECT_EQ(f["violations"][0]["parameter"], "Kx");
  EXPECT_EQ(f["violations"][0]["limit"], "max");
  EXPECT_EQ(f["violations"][0]["bound"], 178.0);
  EXPECT_EQ(f["violations"][0]["unit"], "mV/g");
  EXPECT_NEAR(f["violations"][0]["value"].get<double>(), 181.0, 0.5);
  EXPECT_EQ(f["reason"].get<std::string>().rfind("outside limits: Kx 18", 0), 0u) << f["reason"];
  // The CSV names the same three.
  std::string csv_path = Summary("cal").string();
  csv_path.replace(csv_path.size() - 5, 5, ".csv");
  const std::string csv = Slurp(csv_path);
  EXPECT_NE(csv.find("SN007,fail,outside limits: Kx 18"), std::string::npos) << csv;
  EXPECT_NE(csv.find("SN013,error,"), std::string::npos);
  EXPECT_NE(csv.find("SN017,error,"), std::string::npos);
  // Filed by serial and date: calibration.json is the fit's OUT.
  const std::string folder = by_serial["SN001"]["folder"];
  const std::string date = s["date"];
  EXPECT_EQ(folder, "SN001/" + date);
  const nlohmann::json cal = ReadJson(Path("cal/" + folder + "/calibration.json"));
  EXPECT_EQ(cal["command"], "fit");
  EXPECT_TRUE(cal["converged"].get<bool>());

  // Rerun: every earlier file still there, byte for byte; the new
  // calibrations in date_2 with the change since the first (the same data:
  // exactly 0 sigma).
  std::map<std::string, std::string> before;
  for (const auto& e : fs::recursive_directory_iterator(Path("cal"))) {
    if (e.is_regular_file()) before[e.path().string()] = Slurp(e.path());
  }
  ASSERT_EQ(Run("batch " + man + " -o " + Path("cal")), 0) << Slurp(Path("log.txt"));
  for (const auto& [path, text] : before) {
    ASSERT_TRUE(fs::exists(path)) << path;
    EXPECT_EQ(Slurp(path), text) << path;
  }
  int summaries = 0;
  for (const auto& e : fs::directory_iterator(Path("cal"))) {
    summaries += e.path().extension() == ".json";
  }
  EXPECT_EQ(summaries, 2);
  nlohmann::json again;
  for (const auto& e : fs::directory_iterator(Path("cal"))) {
    if (e.path().extension() == ".json" && !before.count(e.path().string())) {
      again = ReadJson(e.path());
    }
  }
  ASSERT_FALSE(again.is_null());
  for (const nlohmann::json& r : again["results"]) {
    if (r["status"] == "error") continue;
    const std::string serial = r["serial"];
    EXPECT_EQ(r["folder"], serial + "/" + date + "_2");
    EXPECT_EQ(r["previous"], serial + "/" + date);
    EXPECT_EQ(r["largest_change_sigma"], 0.0) << serial;
    EXPECT_GT(r["change_sigma"].size(), 10u);
  }
}

TEST_F(ScaleOut, BatchOnTwoMpiRanksAndAsShardsEqualsOneProcess) {
  std::string manifest = "serial,run,diagnose,Kx_max\n";
  for (int i = 1; i <= 4; ++i) {
    const std::string serial = "U" + std::to_string(i);
    SimulateUnit(serial, 200 + i);
    manifest += serial + ",units/" + serial + "/run.yaml," + (i == 1 ? "true" : "") + ",171.6\n";
  }
  manifest += "MISSING,units/none/run.yaml,,\n";
  const std::string man = WriteText("manifest.csv", manifest);
  const std::string date = " --date 2026-01-31";
  ASSERT_EQ(Run("batch " + man + " -o " + Path("one") + date), 0) << Slurp(Path("log.txt"));
  for (int i = 1; i <= 2; ++i) {
    ASSERT_EQ(
        Run("batch " + man + " -o " + Path("sh") + date + " --shard " + std::to_string(i) + "/2"),
        0);
  }
  ASSERT_EQ(Run("merge " + Summary("sh", "shard-2-of-2").string() + " " +
                Summary("sh", "shard-1-of-2").string() + " -o " + Path("merged.json")),
            0)
      << Slurp(Path("log.txt"));
  const nlohmann::json one = WithoutExecution(ReadJson(Summary("one")));
  EXPECT_EQ(one["units"], 5);
  EXPECT_EQ(one["error"], 1);
  EXPECT_TRUE(one["results"][0]["diagnosed"].get<bool>());
  EXPECT_EQ(WithoutExecution(ReadJson(Path("merged.json"))), one);
  EXPECT_TRUE(fs::exists(Path("merged.csv")));
  std::vector<std::string> dirs = {"sh"};
  if (HaveMpirun()) {
    ASSERT_EQ(RunMpi("batch " + man + " -o " + Path("two") + date), 0) << Slurp(Path("mpi.txt"));
    const nlohmann::json two = ReadJson(Summary("two"));
    EXPECT_EQ(two["execution"]["ranks"], 2);
    EXPECT_EQ(WithoutExecution(two), one);
    dirs.push_back("two");
  }
  // The calibrations themselves, bit for bit but for their timing and
  // provenance (whose command line names the output folder).
  const std::string diagnosis = "U1/2026-01-31/diagnose.json";
  auto bare = [](nlohmann::json j) {
    j.erase("provenance");
    return j;
  };
  for (const std::string& d : dirs) {
    EXPECT_EQ(bare(ReadJson(Path(d + "/" + diagnosis))), bare(ReadJson(Path("one/" + diagnosis))))
        << d;
  }
  for (int i = 1; i <= 4; ++i) {
    const std::string f = "U" + std::to_string(i) + "/2026-01-31/calibration.json";
    nlohmann::json a = ReadJson(Path("one/" + f));
    a.erase("time_s");
    a.erase("provenance");
    for (const std::string& d : dirs) {
      nlohmann::json b = ReadJson(Path(d + "/" + f));
      b.erase("time_s");
      b.erase("provenance");
      EXPECT_EQ(a, b) << d << "/" << f;
    }
  }
  if (!HaveMpirun()) GTEST_SKIP() << "mpirun not installed (Debian: openmpi-bin) or built without MPI: MPI part skipped";
}

}  // namespace
}  // namespace triadcal
