// Typed access to the fields of a YAML file with one-line errors that name the
// file and the key path: "run.yaml: triad.scale_mV_per_g: expected a list of 3
// numbers, got 2". Every reader of a triadcal YAML file goes through these.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace triadcal {

// Where in which file: `where` is the file (or "file: section"), `path` the
// dotted key path inside it. Message() gives "where: path: what".
struct YamlPlace {
  std::string where;
  std::string path;

  YamlPlace Child(const std::string& key) const;  // path + "." + key
  YamlPlace Index(std::size_t i) const;           // path + "[i]"
  std::string Message(const std::string& what) const;
  [[noreturn]] void Fail(const std::string& what) const;  // throws InputError
};

// Loads a YAML file; syntax errors become InputError("FILE:LINE: ...").
YAML::Node LoadYamlFile(const std::string& path);

// Throws when `node` is not a map, holds a key outside `allowed` (the message
// lists the allowed keys, to catch typos) or a key given twice (yaml-cpp would
// silently keep the first).
void CheckKeys(const YAML::Node& node, const YamlPlace& at,
               const std::vector<std::string>& allowed);

// Scalar readers: finite numbers only.
double ReadNumber(const YAML::Node& node, const YamlPlace& at);
double ReadPositive(const YAML::Node& node, const YamlPlace& at);     // > 0
double ReadNonNegative(const YAML::Node& node, const YamlPlace& at);  // >= 0
std::string ReadString(const YAML::Node& node, const YamlPlace& at);
Eigen::Vector3d ReadVector3(const YAML::Node& node, const YamlPlace& at);

// The text of a map key; throws "at: expected a name as key, got a list" for a
// list or map used as a key (YAML allows it, triadcal files never do).
std::string KeyOf(const YAML::Node& key, const YamlPlace& at);

// Short text of a node for messages: the scalar itself, or "a list", "a map".
std::string DescribeNode(const YAML::Node& node);

}  // namespace triadcal
