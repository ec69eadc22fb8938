#include "app/provenance.h"

#include <ctime>
#include <filesystem>
#include <utility>

#include "core/io/sha256.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string AbsolutePath(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}

// A shell word: quoted when it holds anything but safe characters.
std::string ShellWord(const std::string& w) {
  if (!w.empty() && w.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789_-+=./:,@%") == std::string::npos) {
    return w;
  }
  std::string q = "'";
  for (char c : w) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

Provenance::Provenance(std::string version, std::string git_commit, std::string command_line)
    : version_(std::move(version)),
      git_commit_(std::move(git_commit)),
      command_line_(std::move(command_line)) {}

std::string CommandLineOf(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string word = argv[i];
    if (i == 0) word = fs::path(word).filename().string();
    line += (i ? " " : "") + ShellWord(word);
  }
  return line;
}

void Provenance::RecordInput(const std::string& role, const std::string& path) {
  RecordInput(role, path, Sha256OfFile(path));
}

void Provenance::RecordInput(const std::string& role, const std::string& path,
                             const std::string& sha256) {
  const std::string abs = AbsolutePath(path);
  for (const json& in : inputs_) {
    if (in["role"] == role && in["path"] == abs) return;
  }
  inputs_.push_back({{"role", role}, {"path", abs}, {"sha256", sha256}});
}

void Provenance::RecordSensor(const std::string& serial, const std::string& model) {
  sensor_serial_ = serial;
  sensor_model_ = model;
}

json Provenance::Json() const {
  json p;
  p["tool"] = "triadcal";
  p["version"] = version_;
  p["git_commit"] = git_commit_;
  p["date_utc"] = UtcNow();
  p["command_line"] = command_line_;
  p["inputs"] = inputs_;
  if (!sensor_serial_.empty() || !sensor_model_.empty()) {
    p["sensor"] = {{"serial", sensor_serial_}, {"model", sensor_model_}};
  }
  return p;
}

}  // namespace triadcal
