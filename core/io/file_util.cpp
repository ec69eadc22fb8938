#include "core/io/file_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

#include "core/io/temporary_files.h"
#include "core/model/errors.h"

namespace triadcal {

namespace fs = std::filesystem;

namespace {

bool SameFile(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return false;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  auto canonical = [](const std::string& p) {
    std::error_code e;
    const fs::path abs = fs::absolute(p, e);
    if (e) return fs::path(p);
    const fs::path c = fs::weakly_canonical(abs, e);
    return e ? abs.lexically_normal() : c;
  };
  return canonical(a) == canonical(b);
}

// What a stat() mode is, when it is not a regular file.
const char* KindProblem(mode_t mode) {
  if (S_ISDIR(mode)) return "is a directory";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "is a device node, not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  if (!S_ISREG(mode)) return "is not a regular file";
  return "";
}

// What a failed stat() or open() says, in words for a one-line error.
std::string ErrnoProblem(int err) {
  switch (err) {
    case ENOENT:
      return "no such file";
    case ELOOP:
      return "too many levels of symbolic links (a symlink loop?)";
    case ENAMETOOLONG:
      return "file name too long (longer than the system allows)";
    case EACCES:
    case EPERM:
      return "permission denied";
    case ENOTDIR:
      return "a component of the path is not a folder";
    default:
      return std::strerror(err);
  }
}

// The file a write of `path` replaces: a symbolic link to a regular file is
// written through (its target), anything else is `path` itself.
std::string WriteTarget(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    std::error_code ec;
    const fs::path target = fs::canonical(path, ec);
    if (!ec) return target.string();
  }
  return path;
}

}  // namespace

void OutputGuard::NoteInput(const std::string& path) {
  const std::lock_guard<std::mutex> lock(mutex_);
  inputs_.push_back(path);
}

void OutputGuard::NoteOutput(const std::string& path) {
  const std::lock_guard<std::mutex> lock(mutex_);
  for (const std::string& out : outputs_) {
    if (SameFile(out, path)) {
      throw InputError(path + ": given for two outputs (each output needs its own file)");
    }
  }
  outputs_.push_back(path);
}

void OutputGuard::CheckOutputsAreNotInputs(const std::string& path) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> outs = outputs_;
  outs.push_back(path);
  for (const std::string& out : outs) {
    for (const std::string& in : inputs_) {
      if (SameFile(out, in)) {
        throw InputError(out + ": is the input file '" + in +
                         "' (an output never replaces an input; choose another name)");
      }
    }
  }
}

std::string PathForMessage(const std::string& path) {
  return path.size() <= 240 ? path : Excerpt(path, 120);
}

std::string InputFileProblem(const std::string& path) {
  if (path.empty()) return "empty file name";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    struct stat link {};
    if (err == ENOENT && ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
      return "is a symbolic link to a missing file";
    }
    return ErrnoProblem(err);
  }
  const std::string kind = KindProblem(st.st_mode);
  if (!kind.empty()) return kind == "is a directory" ? kind + ", not a file" : kind;
  // Non-blocking: a FIFO put in its place since the stat() is not waited on.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return ErrnoProblem(errno);
  ::close(fd);
  return "";
}

void CheckInputFile(const std::string& path) {
  const std::string problem = InputFileProblem(path);
  if (problem.empty()) return;
  if (problem == "no such file") {
    throw InputError(PathForMessage(path) + ": cannot read (no such file or not readable)");
  }
  throw InputError(PathForMessage(path) + ": cannot read: " + problem);
}

void CheckOutputFile(const std::string& path) {
  if (path.empty()) throw InputError("output: empty file name (give a file name)");
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT) return;  // a new file; its folder is checked when it is written
    throw InputError(PathForMessage(path) + ": cannot write: " + ErrnoProblem(err));
  }
  if (S_ISLNK(st.st_mode)) {
    struct stat target {};
    if (::stat(path.c_str(), &target) != 0) {
      const int err = errno;
      throw InputError(PathForMessage(path) + ": cannot write: is a symbolic link " +
                       (err == ENOENT ? std::string("to a missing file")
                                      : "that cannot be followed (" + ErrnoProblem(err) + ")") +
                       "; outputs are regular files");
    }
    const std::string kind = KindProblem(target.st_mode);
    if (!kind.empty()) {
      throw InputError(PathForMessage(path) + ": cannot write: is a symbolic link to " +
                       kind.substr(3) + "; outputs are regular files");
    }
    return;
  }
  const std::string kind = KindProblem(st.st_mode);
  if (kind.empty()) return;
  if (kind == "is a directory") throw InputError(PathForMessage(path) + ": cannot write: " + kind);
  throw InputError(PathForMessage(path) + ": cannot write: " + kind +
                   "; outputs are written whole, as regular files");
}

std::string ReadFileRange(const std::string& path, std::uintmax_t offset, std::size_t max_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return "";
  struct stat st {};
  std::string out;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    out.resize(max_bytes);
    std::size_t got = 0;
    while (got < max_bytes) {
      const ssize_t n = ::pread(fd, &out[got], max_bytes - got, static_cast<off_t>(offset + got));
      if (n <= 0) break;
      got += static_cast<std::size_t>(n);
    }
    out.resize(got);
  }
  ::close(fd);
  return out;
}

std::string HostTag() {
  char name[256] = "";
  if (::gethostname(name, sizeof(name) - 1) != 0) return "host";
  std::string tag;
  for (const char* c = name; *c && tag.size() < 64; ++c) {
    const bool ok = std::isalnum(static_cast<unsigned char>(*c)) || *c == '-' || *c == '_';
    tag += ok ? *c : '_';
  }
  return tag.empty() ? "host" : tag;
}

bool ProcessIsGone(long pid) {
  if (pid <= 0) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

std::string TemporaryPathFor(const std::string& path) {
  const fs::path target(path);
  return (target.parent_path() /
          (".tmp." + target.filename().string() + "." + HostTag() + "." + std::to_string(getpid())))
      .string();
}

void RemoveStaleEntries(const std::string& folder, const std::string& prefix,
                        bool directories) {
  const fs::path dir = folder.empty() ? fs::path(".") : fs::path(folder);
  const std::string host = HostTag();
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    std::string rest = name.substr(prefix.size());  // HOST.PID, or PID (earlier versions)
    const std::size_t dot = rest.rfind('.');
    if (dot != std::string::npos) {
      if (rest.substr(0, dot) != host) continue;  // another host's: it may be running
      rest = rest.substr(dot + 1);
    }
    if (rest.empty() || rest.size() > 9 ||
        rest.find_first_not_of("0123456789") != std::string::npos) {
      continue;
    }
    const long pid = std::stol(rest);
    if (pid == static_cast<long>(getpid()) || !ProcessIsGone(pid)) continue;
    std::error_code rm;
    const fs::file_status st = fs::symlink_status(it->path(), rm);
    if (directories && fs::is_directory(st)) {
      fs::remove_all(it->path(), rm);
    } else if (!directories && fs::is_regular_file(st)) {
      fs::remove(it->path(), rm);
    }
  }
}

void RemoveStaleTemporaries(const std::string& path) {
  const fs::path target(path);
  RemoveStaleEntries(target.parent_path().string(), ".tmp." + target.filename().string() + ".",
                     false);
}

void WriteFileAtomically(const std::string& path, const std::string& content,
                         const WriteOptions& options) {
  CheckOutputFile(path);
  if (options.guard) options.guard->CheckOutputsAreNotInputs(path);
  const std::string target = WriteTarget(path);
  RemoveStaleTemporaries(target);
  const std::string tmp = TemporaryPathFor(target);
  const TemporaryRegistration registration(options.temporaries, tmp);
  ::unlink(tmp.c_str());  // ours, from an earlier failed attempt of this process
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
  if (fd < 0) throw InputError(path + ": cannot write (folder missing or not writable)");
  struct stat old {};
  if (::stat(target.c_str(), &old) == 0 && S_ISREG(old.st_mode)) {
    ::fchmod(fd, old.st_mode & 07777);  // a replaced file keeps its permissions
  }
  std::size_t done = 0;
  bool ok = true;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ok = false;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) ok = false;
  if (!ok) {
    ::unlink(tmp.c_str());
    throw InputError(path + ": write failed (disk full?)");
  }
  if (::rename(tmp.c_str(), target.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw InputError(path + ": cannot write: " + std::strerror(err));
  }
}

std::string ReadFile(const std::string& path) {
  CheckInputFile(path);
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
