// The JSON reader of parameter files: a key given twice is an error (a plain
// parse keeps the last one), keys of another build are reported, not dropped.
#include "core/io/parameters_json.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"

namespace triadcal {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    ParseJsonStrict(text, "cal.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ParseJsonStrict, KeyGivenTwiceNamesItsPath) {
  EXPECT_EQ(ErrorOf("{\"parameters\": {\"Kx\": 1, \"Ky\": 2, \"Kx\": 3}}"),
            "cal.json: parameters.Kx: given twice (each key once per object; a reader would "
            "keep only one of them)");
  EXPECT_EQ(ErrorOf("{\"a\": 1, \"a\": 2}"),
            "cal.json: a: given twice (each key once per object; a reader would keep only one "
            "of them)");
  EXPECT_EQ(ErrorOf("{\"p\": {\"x\": {\"value\": 1, \"value\": 2}}}"),
            "cal.json: p.x.value: given twice (each key once per object; a reader would keep "
            "only one of them)");
  // The same key in two objects is fine, and so is a list of objects.
  EXPECT_EQ(ErrorOf("{\"a\": {\"v\": 1}, \"b\": {\"v\": 2}, \"c\": [{\"v\": 1}, {\"v\": 2}]}"), "");
  EXPECT_EQ(ParseJsonStrict("{\"a\": {\"v\": 1}}", "x")["a"]["v"], 1);
}

TEST(ParseJsonStrict, SyntaxErrorsAreInputErrors) {
  EXPECT_EQ(ErrorOf("{\"a\": 1e309}").rfind("cal.json: not valid JSON: ", 0), 0u);
  EXPECT_EQ(ErrorOf("{").rfind("cal.json: not valid JSON: line 1, column ", 0), 0u);
}

TEST(ParametersFromJson, UnknownKeysAreListed) {
  const nlohmann::json j = ParseJsonStrict(
      "{\"parameters\": {\"Kx\": 174, \"bogus.tau\": 2, \"Kx.t1\": 0.1, \"angle_latency.tau_ms\": "
      "2, \"Kq\": 1}}",
      "cal.json");
  const ParametersFile f = ParametersFromJson(j, "cal.json", {""}, "a file");
  EXPECT_EQ(f.unknown_keys, (std::vector<std::string>{"Kq", "bogus.tau"}));
  EXPECT_EQ(f.entries.at("angle_latency.tau").value_file, 2.0);
}

}  // namespace
}  // namespace triadcal
