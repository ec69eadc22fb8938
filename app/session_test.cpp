// The session's values (app/session.h): the provenance records each input
// once and two sessions do not share it; the output guard refuses an output
// of other inputs unless the session says --force.
#include "app/session.h"

#include <gtest/gtest.h>

#include <string>

#include "app/output_guard.h"
#include "app/provenance.h"
#include "core/io/sha256.h"
#include "core/model/errors.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

class SessionTest : public testing_fixtures::TempDirTest {};

TEST_F(SessionTest, ProvenanceIsAValue) {
  const std::string run = WriteText("run.yaml", "data: run.csv\n");
  Session a;
  a.provenance = Provenance("1.2.3", "abc", "triadcal fit run.yaml");
  a.provenance.RecordInput("run", run);
  a.provenance.RecordInput("run", run);  // once
  a.provenance.RecordSensor("0042", "ADXL325");
  const nlohmann::json p = a.provenance.Json();
  EXPECT_EQ(p["version"], "1.2.3");
  EXPECT_EQ(p["git_commit"], "abc");
  EXPECT_EQ(p["command_line"], "triadcal fit run.yaml");
  ASSERT_EQ(p["inputs"].size(), 1u);
  EXPECT_EQ(p["inputs"][0]["sha256"], Sha256OfFile(run));
  EXPECT_EQ(p["sensor"]["serial"], "0042");
  const Session b;  // another session knows nothing of a's inputs
  EXPECT_TRUE(b.provenance.inputs().empty());
  EXPECT_FALSE(b.provenance.Json().contains("sensor"));
}

TEST_F(SessionTest, CommandLineIsQuotedForAShell) {
  char prog[] = "/usr/local/bin/triadcal", fit[] = "fit", odd[] = "my run.yaml";
  char* argv[] = {prog, fit, odd};
  EXPECT_EQ(CommandLineOf(3, argv), "triadcal fit 'my run.yaml'");
}

TEST_F(SessionTest, GuardRefusesOtherInputsUnlessForced) {
  const std::string a = WriteText("a.yaml", "a: 1\n"), b = WriteText("b.yaml", "b: 2\n");
  Session first;
  first.provenance.RecordInput("run", a);
  const std::string out = Path("out.json");
  WriteText("out.json", "{\n  \"provenance\": " + first.provenance.Json().dump() + "\n}\n");
  EXPECT_NO_THROW(CheckOverwrite(out, first));  // the same inputs: replaced silently
  Session second;
  second.provenance.RecordInput("run", b);
  EXPECT_THROW(CheckOverwrite(out, second), InputError);
  second.force = true;
  EXPECT_NO_THROW(CheckOverwrite(out, second));
  WriteText("plain.json", "{}\n");
  EXPECT_THROW(CheckOverwrite(Path("plain.json"), first), InputError);  // not a triadcal output
}

}  // namespace
}  // namespace triadcal
