// Typed YAML field access with "FILE: key.path: what is wrong" errors.
#include "core/io/yaml_fields.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {

YamlPlace YamlPlace::Child(const std::string& key) const {
  return {where, path.empty() ? key : path + "." + key};
}

YamlPlace YamlPlace::Index(std::size_t i) const {
  return {where, path + "[" + std::to_string(i) + "]"};
}

std::string YamlPlace::Message(const std::string& what) const {
  // A key path is short; one that is not holds a key read from the file.
  const std::string shown = path.size() <= 160 ? path : Excerpt(path, 100);
  return path.empty() ? where + ": " + what : where + ": " + shown + ": " + what;
}

void YamlPlace::Fail(const std::string& what) const { throw InputError(Message(what)); }

namespace {

// Whether a YAML document holds anything, and where it starts: the events of
// one document from the parser, counted.
class DocumentContent : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Note(mark); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string&) override {
    Note(mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Note(mark);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Note(mark);
  }
  void OnMapEnd() override {}

  bool has_content = false;
  YAML::Mark start;

 private:
  void Note(const YAML::Mark& mark) {
    if (!has_content) start = mark;
    has_content = true;
  }
};

}  // namespace

YAML::Node LoadYamlFile(const std::string& path) {
  CheckInputFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read (no such file or not readable)");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  YAML::Node root;
  try {
    root = YAML::Load(text);
    // One document per file: a second one (after "---") would be ignored,
    // and what it holds with it. Only the first two documents are parsed
    // (YAML::LoadAll never ends on some damaged input); an empty one after a
    // trailing "---" holds nothing.
    std::istringstream again(text);
    YAML::Parser parser(again);
    DocumentContent first, second;
    if (parser.HandleNextDocument(first) && parser.HandleNextDocument(second) &&
        second.has_content) {
      throw InputError(path + ":" + std::to_string(second.start.line + 1) +
                       ": a second YAML document (after ---); a triadcal file holds one (merge "
                       "them, or remove the ---)");
    }
  } catch (const YAML::ParserException& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1) +
                     ": YAML syntax error: " + Excerpt(e.msg, 120));
  }
  return root;
}

std::string DescribeNode(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "'" + Excerpt(node.Scalar()) + "'";
}

std::string KeyOf(const YAML::Node& key, const YamlPlace& at) {
  if (!key.IsScalar()) {
    at.Fail("expected a name as key, got " + DescribeNode(key) + " (a list or map is no key)");
  }
  return key.Scalar();
}

void CheckKeys(const YAML::Node& node, const YamlPlace& at,
               const std::vector<std::string>& allowed) {
  if (!node.IsMap()) at.Fail("expected a map, got " + DescribeNode(node));
  std::set<std::string> seen;
  for (const auto& kv : node) {
    const std::string key = KeyOf(kv.first, at);
    bool ok = false;
    for (const std::string& a : allowed) ok = ok || a == key;
    if (ok) {
      if (!seen.insert(key).second) at.Child(key).Fail("given twice");
      continue;
    }
    std::string list;
    for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
    at.Child(key).Fail("unknown key (allowed: " + list + ")");
  }
}

double ReadNumber(const YAML::Node& node, const YamlPlace& at) {
  if (!node.IsScalar()) at.Fail("expected a number, got " + DescribeNode(node));
  double v = 0.0;
  if (!YAML::convert<double>::decode(node, v)) {
    at.Fail("expected a number, got " + DescribeNode(node));
  }
  if (!std::isfinite(v)) at.Fail("expected a finite number, got " + DescribeNode(node));
  return v;
}

double ReadPositive(const YAML::Node& node, const YamlPlace& at) {
  const double v = ReadNumber(node, at);
  if (!(v > 0.0)) at.Fail("must be > 0, got " + Excerpt(node.Scalar()));
  return v;
}

double ReadNonNegative(const YAML::Node& node, const YamlPlace& at) {
  const double v = ReadNumber(node, at);
  if (v < 0.0) at.Fail("must be >= 0, got " + Excerpt(node.Scalar()));
  return v;
}

std::string ReadString(const YAML::Node& node, const YamlPlace& at) {
  if (!node.IsScalar()) at.Fail("expected a text, got " + DescribeNode(node));
  return node.Scalar();
}

Eigen::Vector3d ReadVector3(const YAML::Node& node, const YamlPlace& at) {
  if (!node.IsSequence()) at.Fail("expected a list of 3 numbers, got " + DescribeNode(node));
  if (node.size() != 3) {
    at.Fail("expected a list of 3 numbers, got " + std::to_string(node.size()));
  }
  Eigen::Vector3d v;
  for (std::size_t i = 0; i < 3; ++i) v[i] = ReadNumber(node[i], at.Index(i));
  return v;
}

}  // namespace triadcal
