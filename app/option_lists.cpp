#include "app/option_lists.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace triadcal {

std::vector<std::string> SplitList(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    // "a, b" as "a,b": the blanks around an item are not part of its name.
    const std::size_t first = item.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    out.push_back(item.substr(first, item.find_last_not_of(" \t") - first + 1));
  }
  return out;
}

std::vector<Effect> ParseEffectList(const std::string& list, const std::string& option) {
  std::vector<Effect> out;
  for (const std::string& item : SplitList(list)) {
    try {
      out.push_back(EffectFromName(item));
    } catch (const std::invalid_argument& e) {
      throw InputError(option + ": " + e.what());
    }
  }
  return out;
}

std::vector<Effect> ParseEffectList(const std::string& list, const RunData& data,
                                    const std::string& option) {
  const std::vector<Effect> effects = ParseEffectList(list, option);
  for (Effect e : effects) {
    const EffectSpec& spec = GetEffectSpec(e);
    if (spec.needs.temp_C && !data.has_temp()) {
      throw InputError(option + ": " + spec.name +
                       " needs a temp_C column, which this run does not have (columns.temp_C "
                       "in run.yaml)");
    }
    if (spec.stage == EffectStage::kGyro && !data.has_gyro()) {
      throw InputError(option + ": " + spec.name +
                       " acts on the gyro, which this run does not have (gx gy gz columns and a "
                       "gyro block in run.yaml)");
    }
  }
  return effects;
}

void CheckHoldFree(const std::vector<std::string>& held, const std::vector<std::string>& freed,
                   const ParameterLayout& layout) {
  for (const std::string& h : held) {
    if (std::find(freed.begin(), freed.end(), h) != freed.end()) {
      throw InputError("--hold/--free: '" + Excerpt(h, 40) + "' given to both: hold it or free it");
    }
  }
  for (int i = 0; i < layout.size(); ++i) {
    if (std::find(held.begin(), held.end(), layout.info(i).name) == held.end()) return;
  }
  throw InputError("--hold: holds every parameter; nothing left to estimate");
}

}  // namespace triadcal
