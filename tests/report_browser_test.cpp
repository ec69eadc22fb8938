// The HTML report in a real browser (Debian's chromium, headless): a report
// made from a real fit of a small simulated run loads with no console
// message and no script error, and every chart has drawn (the page checks the
// pixels of each canvas and records the result in #triadcal-status). The
// failure cases prove the check can fail: a console error, a script error and
// a blank chart (a residual series without values) each make it fail.
// A fit with a gyro triad shows the gyro's own section (verdict, parameters
// with units, residual and spectrum); without one, none.
// Skipped when chromium is absent (TRIADCAL_CHROMIUM names another browser
// binary; set empty, it skips too). A screenshot is kept in
// build/test-artifacts/report.png.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

const char* kScenario = R"(
seed: 7
profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0], duration_s: 60, rate_hz: 25}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, gamma_y: 140, gamma_z: 64,
        Kxx: 0.002, dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  bench: {lever_arm_mm: [138, 20, 20]}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)";

std::string Slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string FindChromium() {
  if (const char* env = std::getenv("TRIADCAL_CHROMIUM")) return env;
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser"}) {
    if (fs::exists(p)) return p;
  }
  return "";
}

std::string Unescape(std::string s) {
  const std::pair<const char*, const char*> entities[] = {
      {"&quot;", "\""}, {"&lt;", "<"}, {"&gt;", ">"}, {"&#39;", "'"}, {"&amp;", "&"}};
  for (const auto& [from, to] : entities) {
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + 1)) {
      s.replace(p, std::string(from).size(), to);
    }
  }
  return s;
}

struct BrowserResult {
  int exit_code = -1;
  std::string status;                // data-status of #triadcal-status
  nlohmann::json result;             // its data-result: {charts, blank, errors}
  std::vector<std::string> console;  // console lines chromium logged
  std::string dom;                   // the page as drawn (--dump-dom)
};

// The drawn report: the <main> element (without the embedded OUT data and
// the inlined scripts, which hold every word).
std::string MainOf(const std::string& dom) {
  const std::size_t a = dom.find("<main id=\"report\">");
  const std::size_t b = dom.find("</main>", a);
  return a == std::string::npos || b == std::string::npos ? "" : dom.substr(a, b - a);
}

// The table row whose first cell is `first` ("" when none).
std::string RowOf(const std::string& html, const std::string& first) {
  const std::size_t a = html.find("<tr><td>" + first + "</td>");
  return a == std::string::npos ? "" : html.substr(a, html.find("</tr>", a) - a);
}

std::size_t Count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

class ReportBrowserTest : public testing_fixtures::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    chromium_ = FindChromium();
  }

  int Run(const std::string& args) const {
    return std::system((std::string(TRIADCAL_BIN) + " " + args + " > " + Path("out.txt") + " 2> " +
                        Path("err.txt"))
                           .c_str());
  }
  std::string Err() const { return Slurp(Path("err.txt")); }

  std::string ChromiumCommand(const std::string& profile) const {
    return "timeout 180 " + chromium_ +
           " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
           " --disable-background-networking --disable-component-update --disable-sync"
           " --hide-scrollbars --user-data-dir=" +
           Path(profile) + " --virtual-time-budget=5000";
  }

  // Loads the page, lets it draw and check itself, and returns what it found
  // plus every console line chromium logged.
  BrowserResult Load(const std::string& html) const {
    static int n = 0;
    const std::string tag = std::to_string(++n);
    BrowserResult r;
    r.exit_code = std::system((ChromiumCommand("profile" + tag) +
                               " --enable-logging=stderr --v=0 --dump-dom file://" + html + " > " +
                               Path("dom" + tag + ".html") + " 2> " + Path("chrome" + tag + ".err"))
                                  .c_str());
    const std::string dom = Slurp(Path("dom" + tag + ".html"));
    r.dom = dom;
    const std::size_t div = dom.find("<div id=\"triadcal-status\"");
    if (div != std::string::npos) {
      const std::string tagtext = dom.substr(div, dom.find('>', div) - div);
      auto attr = [&](const std::string& name) {
        const std::size_t a = tagtext.find(name + "=\"");
        if (a == std::string::npos) return std::string();
        const std::size_t b = a + name.size() + 2;
        return Unescape(tagtext.substr(b, tagtext.find('"', b) - b));
      };
      r.status = attr("data-status");
      const std::string res = attr("data-result");
      if (!res.empty()) r.result = nlohmann::json::parse(res);
    }
    std::istringstream err(Slurp(Path("chrome" + tag + ".err")));
    for (std::string line; std::getline(err, line);) {
      if (line.find(":CONSOLE") != std::string::npos) r.console.push_back(line);
    }
    return r;
  }

  // A fit of a small simulated run with its report; with_gyro, the run has
  // a gyro triad (SPEC section 10).
  void MakeFitReport(const std::string& name, int seed, bool with_gyro = false) {
    std::string scen = kScenario;
    scen.replace(scen.find("seed: 7"), 7, "seed: " + std::to_string(seed));
    if (with_gyro) {
      scen.replace(scen.find("dz2: 4}"), 7,
                   "dz2: 4, gyro.Kx: 1.004, gyro.W0y: -0.5, gyro.Gxy: 0.05}");
      scen.replace(scen.find("angle_arcsec: 15}"), 17, "angle_arcsec: 15, gyro_dps: 0.05}");
      scen.replace(scen.find("  constraints:"), 0, "  gyro: {noise_dps: 0.05}\n");
    }
    WriteText(name + ".yaml", scen);
    ASSERT_EQ(Run("simulate " + Path(name + ".yaml") + " -o " + Path(name)), 0) << Err();
    ASSERT_EQ(Run("fit " + Path(name + "/run.yaml") + " -o " + Path(name + ".json") +
                  " --correlations --report " + Path(name + ".html")),
              0)
        << Err();
  }

  std::string chromium_;
};

std::string Joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

TEST_F(ReportBrowserTest, FitReportLoadsWithEveryChartDrawnAndNoConsoleMessage) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("fit", 7);
  const std::string html = Slurp(Path("fit.html"));
  EXPECT_EQ(html.find("http://"), std::string::npos) << "the report must not load anything";
  EXPECT_EQ(html.find("https://cdn"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);

  const BrowserResult r = Load(Path("fit.html"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  ASSERT_TRUE(r.result.contains("charts"));
  // Residual time series and spectrum.
  EXPECT_GE(r.result["charts"].get<int>(), 2);
  EXPECT_TRUE(r.result["blank"].empty()) << r.result.dump();
  EXPECT_TRUE(r.result["errors"].empty()) << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
  // No gyro, no gyro section.
  ASSERT_FALSE(MainOf(r.dom).empty());
  EXPECT_EQ(MainOf(r.dom).find("Gyro"), std::string::npos);
  // `fit --report` carries the provenance the OUT has.
  const nlohmann::json fit = nlohmann::json::parse(Slurp(Path("fit.json")));
  EXPECT_NE(Slurp(Path("fit.html")).find(fit["provenance"]["version"].get<std::string>()),
            std::string::npos);

  // The screenshot, kept as a test artefact next to the build.
  const fs::path artefacts = fs::path(TRIADCAL_BIN).parent_path().parent_path() / "test-artifacts";
  fs::create_directories(artefacts);
  const std::string png = (artefacts / "report.png").string();
  fs::remove(png);
  EXPECT_EQ(std::system((ChromiumCommand("shot") + " --window-size=1200,2400 --screenshot=" + png +
                         " file://" + Path("fit.html") + " > /dev/null 2>&1")
                            .c_str()),
            0);
  EXPECT_GT(fs::exists(png) ? fs::file_size(png) : 0u, 10000u);
}

TEST_F(ReportBrowserTest, SeveralRunsGiveThePerRunComparison) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("a", 7);
  MakeFitReport("b", 8);
  ASSERT_EQ(Run("report " + Path("a.json") + " " + Path("b.json") + " -o " + Path("ab.html")), 0)
      << Err();
  EXPECT_NE(Slurp(Path("out.txt")).find("(2 outputs)"), std::string::npos);
  const BrowserResult r = Load(Path("ab.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  // Two fits (2 charts each) and the comparison's deviation chart.
  EXPECT_EQ(r.result["charts"].get<int>(), 5) << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
}

// Every command's renderer on one page: each chart draws, nothing logs.
TEST_F(ReportBrowserTest, EveryCommandsReportDraws) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("fit", 7);
  const std::string run = Path("fit/run.yaml");
  ASSERT_EQ(Run("filter " + run + " -o " + Path("filter.json")), 0) << Err();
  ASSERT_EQ(Run("compare " + run + " -o " + Path("compare.json")), 0) << Err();
  ASSERT_EQ(Run("observability " + run + " -o " + Path("obs.json")), 0) << Err();
  ASSERT_EQ(Run("diagnose " + run + " -o " + Path("diag.json") +
                " --candidates angle_latency --truth " + Path("fit/truth.json")),
            0)
      << Err();
  ASSERT_EQ(Run("design " + Path("fit.yaml") + " -o " + Path("design.json") +
                " --durations 30,60,120 --periods 30:12 --amplitudes 360:90 --static-duration 600"),
            0)
      << Err();
  std::string outputs;
  for (const char* f : {"fit", "filter", "compare", "obs", "diag", "design"}) {
    outputs += " " + Path(std::string(f) + ".json");
  }
  ASSERT_EQ(Run("report" + outputs + " -o " + Path("all.html")), 0) << Err();
  const BrowserResult r = Load(Path("all.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  // fit 2, compare 1, observability 1, diagnose 4 (before and after), design
  // 6 groups, the per-run comparison 1.
  EXPECT_EQ(r.result["charts"].get<int>(), 15) << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
}

// What a person files is on the page: the verdict's sentence (never
// "[object Object]"), the provenance (date, version), the noise judged as the
// verdict judges it; the diagnose report's could_hide; a batch summary's
// units with their status.
TEST_F(ReportBrowserTest, WhatAPersonFilesIsOnThePage) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("fit", 7);
  const nlohmann::json fit = nlohmann::json::parse(Slurp(Path("fit.json")));
  const std::string run = Path("fit/run.yaml");
  ASSERT_EQ(Run("diagnose " + run + " -o " + Path("diag.json") +
                " --candidates angle_latency,thermal_drift"),
            0)
      << Err();
  const nlohmann::json diag = nlohmann::json::parse(Slurp(Path("diag.json")));
  ASSERT_FALSE(diag["could_hide"].empty()) << diag["selected"].dump();
  WriteText("manifest.csv", "serial,run,Kx_max\nU1," + run + ",171.6\nMISSING," +
                                Path("none/run.yaml") + ",\n");
  ASSERT_EQ(Run("batch " + Path("manifest.csv") + " -o " + Path("units") + " --date 2026-01-31"),
            0)
      << Err();
  std::string summary;
  for (const auto& e : fs::directory_iterator(Path("units"))) {
    const std::string name = e.path().filename().string();
    if (name.rfind("summary_", 0) == 0 && e.path().extension() == ".json") summary = e.path();
  }
  ASSERT_FALSE(summary.empty());
  ASSERT_EQ(Run("report " + Path("fit.json") + " " + Path("diag.json") + " " + summary + " -o " +
                Path("filed.html")),
            0)
      << Err();
  const BrowserResult r = Load(Path("filed.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
  std::string dom;
  for (int tag = 1; tag < 100 && dom.find("filed") == std::string::npos; ++tag) {
    if (!fs::exists(Path("dom" + std::to_string(tag) + ".html"))) break;
    dom = Slurp(Path("dom" + std::to_string(tag) + ".html"));
  }
  EXPECT_EQ(dom.find("[object Object]"), std::string::npos);
  const std::string sentence = fit["verdict"]["sentence"].get<std::string>();
  EXPECT_NE(dom.find(sentence.substr(0, sentence.find(';'))), std::string::npos) << sentence;
  EXPECT_NE(dom.find("made " + fit["provenance"]["date_utc"].get<std::string>()), std::string::npos);
  EXPECT_NE(dom.find("triadcal " + fit["provenance"]["version"].get<std::string>()),
            std::string::npos);
  const std::string hidden = diag["could_hide"][0]["effect"].get<std::string>() + ": ";
  EXPECT_NE(dom.find(hidden), std::string::npos) << hidden;
  EXPECT_NE(dom.find("Units of "), std::string::npos);
  EXPECT_NE(dom.find("MISSING"), std::string::npos);
  EXPECT_NE(dom.find("2 units: 1 pass, 0 fail, 1 error"), std::string::npos);
}

// A fit with a gyro: its own section with the verdict sentence OUT gives,
// each gyro parameter once (there, not in the accelerometer's table) with
// the unit OUT gives, the gyro's residual and spectrum drawn; no word of a
// broken page.
TEST_F(ReportBrowserTest, GyroFitShowsItsOwnVerdictParametersAndResidual) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("gyro", 7, /*with_gyro=*/true);
  const nlohmann::json fit = nlohmann::json::parse(Slurp(Path("gyro.json")));
  ASSERT_TRUE(fit.contains("gyro")) << "the fit has no gyro block";
  const nlohmann::json& gyro = fit["gyro"];
  ASSERT_TRUE(gyro["verdict"]["sentence"].is_string()) << gyro.dump();
  ASSERT_FALSE(gyro["residual_plot"]["channels"].empty());
  EXPECT_EQ(gyro["residual_plot"]["unit"], "arcsec");

  const BrowserResult r = Load(Path("gyro.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
  // The accelerometer's residual and spectrum, and the gyro's.
  EXPECT_EQ(r.result["charts"].get<int>(), 4) << r.result.dump();
  const std::string page = MainOf(r.dom);
  ASSERT_FALSE(page.empty());
  for (const char* bad : {"[object Object]", "undefined", "NaN"}) {
    EXPECT_EQ(page.find(bad), std::string::npos) << bad;
  }
  EXPECT_NE(page.find("Gyro triad"), std::string::npos);
  EXPECT_NE(page.find(gyro["verdict"]["sentence"].get<std::string>()), std::string::npos)
      << gyro["verdict"]["sentence"];
  EXPECT_NE(page.find("Residual time series (gyro)"), std::string::npos);
  EXPECT_NE(page.find("Residual spectrum (gyro)"), std::string::npos);
  // SPEC section 10's units, as OUT gives them, on the parameter's row.
  for (const auto& [name, unit] : {std::pair<const char*, const char*>{"gyro.Kx", "1"},
                                   {"gyro.W0y", "deg/s"},
                                   {"gyro.beta_z", "arcmin"},
                                   {"gyro.Gxy", "(deg/s)/g"}}) {
    EXPECT_EQ(fit["parameters"][name]["unit"], unit) << name;
    EXPECT_EQ(Count(page, "<tr><td>" + std::string(name) + "</td>"), 1u) << name;
    EXPECT_NE(RowOf(page, name).find("<td>" + std::string(unit) + "</td>"), std::string::npos)
        << RowOf(page, name);
  }
  // The gyro's noise with its unit.
  EXPECT_NE(RowOf(page, "gx").find("<td>" + gyro["noise"]["unit"].get<std::string>() + "</td>"),
            std::string::npos)
      << RowOf(page, "gx");
  // The accelerometer's table is still there, without the gyro's rows.
  EXPECT_NE(RowOf(page, "Kx").find("<td>"), std::string::npos);
}

// A joint fit of runs with a gyro: the page says which runs' gyro the joint
// problem leaves out (OUT's gyro_not_calibrated), as the command's warning
// does.
TEST_F(ReportBrowserTest, JointFitSaysWhichGyroItDoesNotCalibrate) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("g1", 7, /*with_gyro=*/true);
  MakeFitReport("g2", 8, /*with_gyro=*/true);
  ASSERT_EQ(Run("fit " + Path("g1/run.yaml") + " " + Path("g2/run.yaml") + " -o " +
                Path("joint.json")),
            0)
      << Err();
  ASSERT_EQ(Run("report " + Path("joint.json") + " -o " + Path("joint.html")), 0) << Err();
  const BrowserResult r = Load(Path("joint.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
  const std::string page = MainOf(r.dom);
  EXPECT_NE(page.find("gyro not calibrated here (runs g1, g2): several runs together calibrate "
                      "the accelerometer triad only"),
            std::string::npos)
      << page.substr(0, 2000);
}

// diagnose on a run with a gyro: the report shows the gyro's verdict before
// and after the loop, and its residual before and after.
TEST_F(ReportBrowserTest, GyroDiagnoseShowsTheGyroBeforeAndAfter) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("gyro", 7, /*with_gyro=*/true);
  ASSERT_EQ(Run("diagnose " + Path("gyro/run.yaml") + " -o " + Path("diag.json") +
                " --candidates angle_latency,thermal_drift --report " + Path("diag.html")),
            0)
      << Err();
  const nlohmann::json diag = nlohmann::json::parse(Slurp(Path("diag.json")));
  ASSERT_TRUE(diag["after"]["gyro"]["verdict"]["sentence"].is_string()) << diag["after"].dump();
  const BrowserResult r = Load(Path("diag.html"));
  EXPECT_EQ(r.status, "ok") << r.result.dump();
  EXPECT_TRUE(r.console.empty()) << Joined(r.console);
  const std::string page = MainOf(r.dom);
  ASSERT_FALSE(page.empty());
  for (const char* bad : {"[object Object]", "undefined", "NaN"}) {
    EXPECT_EQ(page.find(bad), std::string::npos) << bad;
  }
  EXPECT_NE(page.find("Gyro triad, before and after"), std::string::npos);
  for (const char* state : {"before", "after"}) {
    const std::string sentence = diag[state]["gyro"]["verdict"]["sentence"].get<std::string>();
    EXPECT_NE(page.find(std::string(state) + ": " + sentence), std::string::npos) << sentence;
  }
  EXPECT_NE(page.find("Residual time series (gyro, after)"), std::string::npos);
  EXPECT_NE(page.find("Residual time series (gyro, before)"), std::string::npos);
  EXPECT_EQ(Count(page, "<tr><td>gyro.W0y</td>"), 1u);
}

// The check fails when it should: a console error, a script error, or a
// chart with nothing drawn.
TEST_F(ReportBrowserTest, CheckFailsOnConsoleErrorScriptErrorAndBlankChart) {
  if (chromium_.empty()) GTEST_SKIP() << "chromium is not installed (setup.sh installs it)";
  MakeFitReport("fit", 7);
  const std::string html = Slurp(Path("fit.html"));
  const std::string anchor = "<main id=\"report\">";
  ASSERT_NE(html.find(anchor), std::string::npos);

  std::string with_console = html;
  with_console.insert(with_console.find(anchor), "<script>console.error('injected')</script>");
  WriteText("console.html", with_console);
  const BrowserResult c = Load(Path("console.html"));
  EXPECT_EQ(c.status, "fail");
  EXPECT_EQ(c.console.size(), 1u) << Joined(c.console);
  EXPECT_NE(c.result.dump().find("console.error: injected"), std::string::npos) << c.result.dump();

  std::string with_throw = html;
  with_throw.insert(with_throw.find(anchor), "<script>null.f()</script>");
  WriteText("throw.html", with_throw);
  const BrowserResult t = Load(Path("throw.html"));
  EXPECT_EQ(t.status, "fail");
  EXPECT_FALSE(t.console.empty());

  // A residual series with no values: the chart has axes but nothing drawn.
  nlohmann::json out = nlohmann::json::parse(Slurp(Path("fit.json")));
  for (auto& ch : out["residual_plot"]["channels"]) {
    for (auto& v : ch["values"]) v = nullptr;
  }
  WriteText("blank.json", out.dump());
  ASSERT_EQ(Run("report " + Path("blank.json") + " -o " + Path("blank.html")), 0) << Err();
  const BrowserResult b = Load(Path("blank.html"));
  EXPECT_EQ(b.status, "fail");
  ASSERT_TRUE(b.result.contains("blank")) << b.result.dump();
  ASSERT_EQ(b.result["blank"].size(), 1u) << b.result.dump();
  EXPECT_EQ(b.result["blank"][0], "Residual time series");
  EXPECT_TRUE(b.console.empty()) << Joined(b.console);
}

}  // namespace
}  // namespace triadcal
