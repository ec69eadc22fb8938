// Fuzz target: a constraint expression ("2*dpsi - 0.5 * dlambda2") and, when
// the input is valid YAML, the whole `constraints:` list parser.
#include <yaml-cpp/yaml.h>

#include "core/io/constraint_parser.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const triadcal::YamlPlace at{"fuzz.yaml", "constraints"};
  triadcal_fuzz::ExpectOnlyInputErrors([&] { triadcal::ParseConstraintExpr(text, at); });
  YAML::Node node;
  try {
    node = YAML::Load(text);  // YAML syntax is LoadYamlFile's job, not this target's
  } catch (const YAML::Exception&) {
    return 0;
  }
  triadcal_fuzz::ExpectOnlyInputErrors([&] { triadcal::ParseConstraints(node, at); });
  return 0;
}
