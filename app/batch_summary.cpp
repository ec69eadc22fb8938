#include "app/batch_summary.h"

#include <cstdio>
#include <sstream>

#include "core/model/errors.h"

namespace triadcal {
namespace {

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

nlohmann::json UnitResultJson(const UnitResult& u) {
  nlohmann::json v = nlohmann::json::array();
  for (const LimitViolation& x : u.violations) v.push_back(ViolationJson(x));
  return {{"item", u.item},
          {"serial", u.serial},
          {"run", u.run},
          {"status", u.status},
          {"reason", u.reason},
          {"violations", v},
          {"folder", u.folder},
          {"previous", u.previous},
          {"change_sigma", u.change_sigma},
          {"largest_change_parameter", u.largest_change_parameter},
          {"largest_change_sigma", u.largest_change_sigma},
          {"diagnosed", u.diagnosed},
          {"diagnose_selected", u.diagnose_selected},
          {"warnings", u.warnings},
          {"time_s", u.seconds}};
}

UnitResult UnitResultFromJson(const nlohmann::json& j) {
  UnitResult u;
  u.item = j.at("item").get<int>();
  u.serial = j.at("serial").get<std::string>();
  u.run = j.at("run").get<std::string>();
  u.status = j.at("status").get<std::string>();
  u.reason = j.at("reason").get<std::string>();
  for (const nlohmann::json& v : j.at("violations")) u.violations.push_back(ViolationFromJson(v));
  u.folder = j.at("folder").get<std::string>();
  u.previous = j.at("previous").get<std::string>();
  u.change_sigma = j.at("change_sigma");
  u.largest_change_parameter = j.at("largest_change_parameter").get<std::string>();
  u.largest_change_sigma = j.at("largest_change_sigma").get<double>();
  u.diagnosed = j.at("diagnosed").get<bool>();
  u.diagnose_selected = j.at("diagnose_selected").get<std::vector<std::string>>();
  u.warnings = j.at("warnings").get<std::vector<std::string>>();
  u.seconds = j.at("time_s").get<double>();
  return u;
}

BatchCounts CountUnits(const std::vector<UnitResult>& units) {
  BatchCounts c;
  for (const UnitResult& u : units) {
    if (u.status == "pass")
      ++c.pass;
    else if (u.status == "fail")
      ++c.fail;
    else
      ++c.error;
  }
  return c;
}

std::string BatchSummaryCsv(const std::vector<UnitResult>& units) {
  std::ostringstream out;
  out << "serial,status,reason,folder,previous,largest_change_sigma,largest_change_parameter,run\n";
  for (const UnitResult& u : units) {
    char change[32] = "";
    if (!u.previous.empty()) std::snprintf(change, sizeof change, "%.3f", u.largest_change_sigma);
    out << CsvField(u.serial) << "," << u.status << "," << CsvField(u.reason) << ","
        << CsvField(u.folder) << "," << CsvField(u.previous) << "," << change << ","
        << CsvField(u.largest_change_parameter) << "," << CsvField(u.run) << "\n";
  }
  return out.str();
}

nlohmann::json BatchSummaryJson(const std::string& manifest, const std::string& output_dir,
                                const std::string& date, const std::vector<UnitResult>& units,
                                const nlohmann::json& execution) {
  const BatchCounts c = CountUnits(units);
  nlohmann::json results = nlohmann::json::array();
  for (const UnitResult& u : units) results.push_back(UnitResultJson(u));
  return {{"command", "batch"},    {"manifest", manifest},  {"output_dir", output_dir},
          {"date", date},          {"units", units.size()}, {"pass", c.pass},
          {"fail", c.fail},        {"error", c.error},      {"results", results},
          {"execution", execution}};
}

nlohmann::json MergeBatchShards(const std::vector<nlohmann::json>& shards,
                                const std::vector<std::string>& paths) {
  const nlohmann::json& first = shards.at(0);
  const nlohmann::json& fs = first["shard"];
  const int count = fs.value("count", 0), items = fs.value("manifest_units", -1);
  std::vector<int> owner(std::max(count, 0), -1);
  std::vector<UnitResult> units(std::max(items, 0));
  std::vector<bool> have(units.size(), false);
  double seconds = 0.0;
  int ranks = 0;
  for (std::size_t f = 0; f < shards.size(); ++f) {
    const nlohmann::json& s = shards[f];
    const nlohmann::json& sh = s["shard"];
    if (s["manifest"] != first["manifest"] || sh.value("manifest_units", -1) != items ||
        s["output_dir"] != first["output_dir"]) {
      throw InputError(paths[f] + ": shard: not the batch of " + paths[0] +
                       " (manifest or output folder differ)");
    }
    const int i = sh.value("index", 0);
    if (sh.value("count", 0) != count || i < 1 || i > count) {
      throw InputError(paths[f] + ": shard: " + std::to_string(i) + "/" +
                       std::to_string(sh.value("count", 0)) + " does not belong to a job of " +
                       std::to_string(count) + " shards");
    }
    if (owner[i - 1] >= 0) {
      throw InputError(paths[f] + ": shard: " + std::to_string(i) + "/" + std::to_string(count) +
                       " given twice (also " + paths[owner[i - 1]] + ")");
    }
    owner[i - 1] = static_cast<int>(f);
    for (const nlohmann::json& r : s.at("results")) {
      UnitResult u = UnitResultFromJson(r);
      if (u.item < 0 || u.item >= items || have[u.item]) {
        throw InputError(paths[f] + ": results: manifest item " + std::to_string(u.item) +
                         " out of range or repeated");
      }
      have[u.item] = true;
      units[u.item] = std::move(u);
    }
    seconds += s["execution"].value("time_s", 0.0);
    ranks += s["execution"].value("ranks", 1);
  }
  for (int i = 0; i < count; ++i) {
    if (owner[i] < 0) {
      throw InputError(paths[0] + ": shard: shard " + std::to_string(i + 1) + "/" +
                       std::to_string(count) + " is missing from the merge");
    }
  }
  for (std::size_t k = 0; k < have.size(); ++k) {
    if (!have[k]) {
      throw InputError(paths[0] + ": shard: manifest item " + std::to_string(k) +
                       " is in no shard");
    }
  }
  nlohmann::json execution = {{"shards", count}, {"ranks", ranks}, {"time_s", seconds}};
  return BatchSummaryJson(first["manifest"].get<std::string>(),
                          first["output_dir"].get<std::string>(), first["date"].get<std::string>(),
                          units, execution);
}

}  // namespace triadcal
