// Reader of MATLAB files through matio: the wanted variables, each a real
// numeric vector, converted to double.
#include <matio.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "core/io/data_table.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {

using MatFile = std::unique_ptr<mat_t, int (*)(mat_t*)>;
using MatVar = std::unique_ptr<matvar_t, void (*)(matvar_t*)>;

template <typename T>
void Convert(const void* data, std::size_t n, std::vector<double>* out) {
  const T* p = static_cast<const T*>(data);
  out->resize(n);
  for (std::size_t i = 0; i < n; ++i) (*out)[i] = static_cast<double>(p[i]);
}

const char* ClassName(matio_classes c) {
  switch (c) {
    case MAT_C_CELL:
      return "cell";
    case MAT_C_STRUCT:
      return "struct";
    case MAT_C_OBJECT:
      return "object";
    case MAT_C_CHAR:
      return "char";
    case MAT_C_SPARSE:
      return "sparse";
    case MAT_C_FUNCTION:
      return "function";
    default:
      return "non-numeric";
  }
}

// Fills *out; returns an empty string, or what is wrong with the variable.
std::string ToVector(const matvar_t& v, std::vector<double>* out) {
  if (v.isComplex) return "complex, expected real numbers";
  if (v.isLogical) return "logical, expected numbers";
  std::size_t n = 1, non_singleton = 0;
  for (int d = 0; d < v.rank; ++d) {
    n *= v.dims[d];
    non_singleton += v.dims[d] != 1;
  }
  if (non_singleton > 1) {
    return "a " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) +
           " matrix, expected a vector";
  }
  if (n > 0 && v.data == nullptr) return "no data";
  switch (v.class_type) {
    case MAT_C_DOUBLE:
      Convert<double>(v.data, n, out);
      break;
    case MAT_C_SINGLE:
      Convert<float>(v.data, n, out);
      break;
    case MAT_C_INT8:
      Convert<std::int8_t>(v.data, n, out);
      break;
    case MAT_C_UINT8:
      Convert<std::uint8_t>(v.data, n, out);
      break;
    case MAT_C_INT16:
      Convert<std::int16_t>(v.data, n, out);
      break;
    case MAT_C_UINT16:
      Convert<std::uint16_t>(v.data, n, out);
      break;
    case MAT_C_INT32:
      Convert<std::int32_t>(v.data, n, out);
      break;
    case MAT_C_UINT32:
      Convert<std::uint32_t>(v.data, n, out);
      break;
    case MAT_C_INT64:
      Convert<std::int64_t>(v.data, n, out);
      break;
    case MAT_C_UINT64:
      Convert<std::uint64_t>(v.data, n, out);
      break;
    default:
      return std::string("not numeric (class ") + ClassName(v.class_type) + ")";
  }
  return "";
}

// What matio logged while reading (errors and warnings: a damaged file).
std::string* g_mat_log = nullptr;

void CaptureMatLog(int level, char* message) {
  if (g_mat_log && level <= MATIO_LOG_LEVEL_WARNING && g_mat_log->empty() && message) *g_mat_log = message;
}

// Sets the matio log to *out for its lifetime (matio's default prints to stderr).
class MatLogCapture {
 public:
  explicit MatLogCapture(std::string* out) {
    g_mat_log = out;
    Mat_LogInitFunc("triadcal", &CaptureMatLog);
  }
  ~MatLogCapture() { g_mat_log = nullptr; }
  MatLogCapture(const MatLogCapture&) = delete;
  MatLogCapture& operator=(const MatLogCapture&) = delete;
};

std::uint32_t ReadU32(const unsigned char* p, bool swap) {
  return swap ? (std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 |
                 std::uint32_t(p[2]) << 8 | p[3])
              : (std::uint32_t(p[3]) << 24 | std::uint32_t(p[2]) << 16 |
                 std::uint32_t(p[1]) << 8 | p[0]);
}

// A MAT v5 file is a 128-byte header and top-level data elements, each an
// 8-byte tag (type, byte count) and its bytes. Every element must end inside
// the file: a file cut short is damaged (matio would read zeros or garbage).
void CheckMat5Elements(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(path + ": cannot read (no such file or not readable)");
  unsigned char header[128];
  if (std::fread(header, 1, 128, f.get()) != 128) {
    throw InputError(path + ": damaged MATLAB file (shorter than its 128-byte header)");
  }
  const bool swap = header[126] == 'M' && header[127] == 'I';
  const std::uintmax_t size = std::filesystem::file_size(path);
  std::uintmax_t pos = 128;
  int element = 0;
  while (pos < size) {
    ++element;
    unsigned char tag[8];
    if (std::fseek(f.get(), static_cast<long>(pos), SEEK_SET) != 0 ||
        std::fread(tag, 1, 8, f.get()) != 8) {
      throw InputError(path + ": damaged MATLAB file (truncated in the tag of element " +
                       std::to_string(element) + ")");
    }
    const std::uint32_t type = ReadU32(tag, swap);
    std::uintmax_t bytes = ReadU32(tag + 4, swap);
    if ((type >> 16) != 0) bytes = 0;  // small data element: data in the tag
    if (type != 15) bytes = (bytes + 7) / 8 * 8;  // miCOMPRESSED is not padded
    const std::uintmax_t end = pos + 8 + bytes;
    if (end > size) {
      throw InputError(path + ": damaged MATLAB file (element " + std::to_string(element) +
                       " declares " + std::to_string(bytes) + " bytes, but the file ends " +
                       std::to_string(size - pos - 8) + " bytes after its tag: truncated?)");
    }
    pos = end;
  }
}

std::size_t ElementBytes(matio_classes c) {
  switch (c) {
    case MAT_C_INT8:
    case MAT_C_UINT8:
      return 1;
    case MAT_C_INT16:
    case MAT_C_UINT16:
      return 2;
    case MAT_C_SINGLE:
    case MAT_C_INT32:
    case MAT_C_UINT32:
      return 4;
    default:
      return 8;
  }
}

}  // namespace

DataTable ReadMatTable(const std::string& path, const std::vector<std::string>& wanted) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(path + ": cannot read (no such file or not readable)");
  }
  NoteInputFile(path);
  std::string log;
  const MatLogCapture capture(&log);
  MatFile mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY), &Mat_Close);
  if (!mat) throw InputError(path + ": not a MATLAB file that matio can read");
  if (Mat_GetVersion(mat.get()) == MAT_FT_MAT5) CheckMat5Elements(path);
  const std::uintmax_t file_bytes = std::filesystem::file_size(path);
  DataTable table;
  table.path = path;
  table.is_mat = true;
  std::size_t n_vars = 0;
  if (char** dir = Mat_GetDir(mat.get(), &n_vars)) {
    for (std::size_t i = 0; i < n_vars; ++i) table.names.push_back(dir[i]);
  }
  if (!log.empty()) throw InputError(path + ": damaged MATLAB file (matio: " + log + ")");
  std::string first;  // the first variable read, for length messages
  for (const std::string& name : wanted) {
    if (table.columns.count(name)) continue;
    {  // declared size against the file size before reading (deflate packs <= 1032:1)
      MatVar info(Mat_VarReadInfo(mat.get(), name.c_str()), &Mat_VarFree);
      if (!info) {
        if (!log.empty()) {
          throw InputError(path + ": damaged MATLAB file (matio: " + log + ")");
        }
        continue;
      }
      long double bytes = static_cast<long double>(ElementBytes(info->class_type));
      for (int d = 0; d < info->rank; ++d) bytes *= static_cast<long double>(info->dims[d]);
      const long double room = static_cast<long double>(file_bytes) *
                               (info->compression == MAT_COMPRESSION_NONE ? 1.0L : 1032.0L);
      if (info->class_type != MAT_C_CELL && info->class_type != MAT_C_STRUCT &&
          bytes > room + 1024.0L) {
        throw InputError(path + ": damaged MATLAB file (variable '" + name + "' declares " +
                         std::to_string(info->dims[0]) + "x" +
                         std::to_string(info->rank > 1 ? info->dims[1] : 1) + " values, more " +
                         "than the " + std::to_string(file_bytes) + "-byte file can hold)");
      }
    }
    MatVar var(Mat_VarRead(mat.get(), name.c_str()), &Mat_VarFree);
    if (!log.empty()) {
      throw InputError(path + ": damaged MATLAB file (matio, reading variable '" + name +
                       "': " + log + ")");
    }
    if (!var) continue;
    std::vector<double> values;
    const std::string problem = ToVector(*var, &values);
    if (!problem.empty()) throw InputError(path + ": variable '" + name + "': " + problem);
    if (first.empty()) {
      first = name;
      table.rows = values.size();
    } else if (values.size() != table.rows) {
      throw InputError(path + ": variable '" + name + "': " + std::to_string(values.size()) +
                       " samples, but '" + first + "' has " + std::to_string(table.rows));
    }
    table.columns[name] = std::move(values);
  }
  return table;
}

}  // namespace triadcal
