#include "core/io/file_util.h"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <unistd.h>

#include <vector>

#include "core/model/errors.h"

namespace triadcal {

namespace fs = std::filesystem;

namespace {

// Readers note their files from several threads at once (`batch` loads its
// units in parallel: ASan found the race on `inputs`), so every access holds
// the mutex.
struct OutputGuard {
  std::mutex mutex;
  bool on = false;
  std::vector<std::string> inputs, outputs;
};

OutputGuard& Guard() {
  static OutputGuard guard;
  return guard;
}

bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  const fs::path ca = fs::weakly_canonical(fs::absolute(a), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b), ec);
  return ca == cb;
}

}  // namespace

void EnableOutputGuard() {
  const std::lock_guard<std::mutex> lock(Guard().mutex);
  Guard().on = true;
}

void DisableOutputGuard() {
  OutputGuard& g = Guard();
  const std::lock_guard<std::mutex> lock(g.mutex);
  g.on = false;
  g.inputs.clear();
  g.outputs.clear();
}

void NoteInputFile(const std::string& path) {
  OutputGuard& g = Guard();
  const std::lock_guard<std::mutex> lock(g.mutex);
  if (g.on) g.inputs.push_back(path);
}

void NoteOutputFile(const std::string& path) {
  OutputGuard& g = Guard();
  const std::lock_guard<std::mutex> lock(g.mutex);
  if (!g.on) return;
  for (const std::string& out : g.outputs) {
    if (SameFile(out, path)) {
      throw InputError(path + ": given for two outputs (each output needs its own file)");
    }
  }
  g.outputs.push_back(path);
}

void CheckOutputsAreNotInputs(const std::string& path) {
  OutputGuard& g = Guard();
  const std::lock_guard<std::mutex> lock(g.mutex);
  if (!g.on) return;
  std::vector<std::string> outs = g.outputs;
  outs.push_back(path);
  for (const std::string& out : outs) {
    for (const std::string& in : g.inputs) {
      if (SameFile(out, in)) {
        throw InputError(out + ": is the input file '" + in +
                         "' (an output never replaces an input; choose another name)");
      }
    }
  }
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  CheckOutputsAreNotInputs(path);
  const fs::path target(path);
  const fs::path tmp =
      target.parent_path() / (".tmp." + target.filename().string() + "." + std::to_string(getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path + ": cannot write (folder missing or not writable)");
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      out.close();
      fs::remove(tmp);
      throw InputError(path + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp);
    throw InputError(path + ": cannot write: " + ec.message());
  }
}

std::string ReadFile(const std::string& path) {
  NoteInputFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read (no such file or not readable)");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string FormatDouble(double x) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), x);
  return std::string(buf, res.ptr);
}

std::string ResolveDataPath(const std::string& referring_file, const std::string& path) {
  const std::string prefix = "shared:";
  const fs::path base = fs::absolute(fs::path(referring_file)).parent_path();
  if (path.rfind(prefix, 0) != 0) {
    const fs::path p(path);
    return (p.is_absolute() ? p : (base / p)).lexically_normal().string();
  }
  const std::string rest = path.substr(prefix.size());
  if (const char* env = std::getenv("TRIADCAL_SHARED"); env && *env) {
    return (fs::path(env) / rest).lexically_normal().string();
  }
  for (fs::path dir = base; !dir.empty(); dir = dir.parent_path()) {
    const fs::path candidate = dir / "shared";
    if (fs::is_directory(candidate) && fs::exists(candidate / rest)) {
      return (candidate / rest).lexically_normal().string();
    }
    if (dir == dir.parent_path()) break;
  }
  return "";
}

}  // namespace triadcal
