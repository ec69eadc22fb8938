// `triadcal report`: bad inputs give one exact line on stderr, exit 2 and no
// output file; the page is self-contained and text from OUT files cannot end
// its script elements. (The browser test is report_browser_test.cpp.)
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

class ReportCommandTest : public testing_fixtures::TempDirTest {
 protected:
  int Run(const std::string& args) const {
    const int rc = std::system((std::string(TRIADCAL_BIN) + " " + args + " > " + Path("out.txt") +
                                " 2> " + Path("err.txt"))
                                   .c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  }
  std::string Slurp(const std::string& path) const {
    std::ifstream f(path, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
  std::string Err() const { return Slurp(Path("err.txt")); }
  void Fails(const std::string& input, const std::string& message) {
    std::filesystem::remove(Path("r.html"));
    EXPECT_EQ(Run("report " + input + " -o " + Path("r.html")), 2);
    EXPECT_EQ(Err(), "triadcal: error: " + message + "\n");
    EXPECT_FALSE(std::filesystem::exists(Path("r.html")));
  }
};

TEST_F(ReportCommandTest, BadInputsGiveOneExactLine) {
  const std::string good = WriteText("good.json", R"({"command": "fit", "parameters": {}})");
  const std::string broken = WriteText("broken.json", "{\n  \"command\": \"fit\",\n  oops\n}\n");
  const std::string foreign = WriteText("foreign.json", R"({"parameters": {}})");
  Fails(good + " " + broken, broken + ":3: not valid JSON");
  Fails(foreign, foreign + ": command: missing; not a triadcal output file");
  Fails(Path("missing.json"),
        Path("missing.json") + ": cannot read (no such file or not readable)");
}

TEST_F(ReportCommandTest, PageIsSelfContainedAndOutTextCannotEndAScript) {
  const std::string out =
      WriteText("o.json", R"({"command": "fit", "verdict": "</script><script>alert(1)</script><!--",
                    "parameters": {"Kx": {"value": 171.5, "sigma": 0.08, "unit": "mV/g"}}})");
  ASSERT_EQ(Run("report " + out + " -o " + Path("r.html")), 0) << Err();
  const std::string html = Slurp(Path("r.html"));
  // Four script elements: the error recorder, the data, uPlot, the report.
  std::size_t closes = 0;
  for (std::size_t p = html.find("</script>"); p != std::string::npos;
       p = html.find("</script>", p + 1)) {
    ++closes;
  }
  EXPECT_EQ(closes, 4u);
  EXPECT_NE(html.find("\\u003c/script>\\u003cscript>alert(1)"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_NE(html.find("uPlot"), std::string::npos);
}

}  // namespace
}  // namespace triadcal
