// Reader of MATLAB files through matio: the wanted variables, each a real
// numeric vector, converted to double. What is damaged is found by the
// reader's own checks (the v5 element walk, the declared sizes, what matio
// returns) and said in its own words: matio's log hook is one C function for
// the whole process, with no pointer of the caller's, so it is not captured.
#include <matio.h>
#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

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

std::uint32_t ReadU32(const unsigned char* p, bool swap) {
  return swap ? (std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 |
                 std::uint32_t(p[2]) << 8 | p[3])
              : (std::uint32_t(p[3]) << 24 | std::uint32_t(p[2]) << 16 |
                 std::uint32_t(p[1]) << 8 | p[0]);
}

// MAT-5 data types ("MAT-File Format", MathWorks, table 1-1).
enum : std::uint32_t {
  kMiInt8 = 1,
  kMiUint8 = 2,
  kMiInt16 = 3,
  kMiUint16 = 4,
  kMiInt32 = 5,
  kMiUint32 = 6,
  kMiSingle = 7,
  kMiDouble = 9,
  kMiInt64 = 12,
  kMiUint64 = 13,
  kMiMatrix = 14,
  kMiCompressed = 15,
  kMiUtf8 = 16,
  kMiUtf16 = 17,
  kMiUtf32 = 18,
};

// Bytes of one value of a numeric data type; 0 for any other type.
std::size_t NumericTypeBytes(std::uint32_t type) {
  switch (type) {
    case kMiInt8:
    case kMiUint8:
      return 1;
    case kMiInt16:
    case kMiUint16:
      return 2;
    case kMiInt32:
    case kMiUint32:
    case kMiSingle:
      return 4;
    case kMiDouble:
    case kMiInt64:
    case kMiUint64:
      return 8;
    default:
      return 0;
  }
}

const char* TextTypeName(std::uint32_t type) {
  return type == kMiUtf8 ? "miUTF8" : type == kMiUtf16 ? "miUTF16" : "miUTF32";
}

// MAT-5 array classes (mxDOUBLE_CLASS = 6 ... mxUINT64_CLASS = 15) hold numbers.
bool IsNumericClass(std::uint32_t c) { return c >= 6 && c <= 15; }

const char* ArrayClassName(std::uint32_t c) {
  static const char* const names[] = {"?",      "cell",   "struct", "object", "char",  "sparse",
                                      "double", "single", "int8",   "uint8",  "int16", "uint16",
                                      "int32",  "uint32", "int64",  "uint64"};
  return c < 16 ? names[c] : "?";
}

// Bytes of one value of a numeric class, as ElementBytes below.
std::size_t ClassValueBytes(std::uint32_t c) {
  switch (c) {
    case 8:
    case 9:
      return 1;
    case 10:
    case 11:
      return 2;
    case 7:
    case 12:
    case 13:
      return 4;
    default:
      return 8;
  }
}

// Reads n bytes at `offset` of an element's content; false when they are not
// there (past the end, or past what was kept of a compressed element).
using ContentReader = std::function<bool(std::uint64_t offset, std::size_t n, unsigned char* out)>;

// The tag of a data element (or of a sub-element): its type, its byte count,
// where its data start and where the next element starts. The small format
// (byte count <= 4 in the upper half of the first word) keeps its data in the tag.
struct Tag {
  std::uint32_t type = 0;
  std::uint64_t bytes = 0, data_at = 0, next = 0;
  bool small = false;
};

bool ReadTag(const ContentReader& read, std::uint64_t at, bool swap, Tag* t) {
  unsigned char b[8];
  if (!read(at, 8, b)) return false;
  const std::uint32_t w0 = ReadU32(b, swap);
  if ((w0 >> 16) != 0) {
    t->type = w0 & 0xFFFF;
    t->bytes = w0 >> 16;
    t->data_at = at + 4;
    t->next = at + 8;
    t->small = true;
  } else {
    t->type = w0;
    t->bytes = ReadU32(b + 4, swap);
    t->data_at = at + 8;
    t->next = at + 8 + (t->bytes + 7) / 8 * 8;
  }
  return true;
}

// What is wrong with the content of a miMATRIX element of `size` bytes
// (after its tag), "" when nothing: the sub-elements (array flags,
// dimensions, name, real and imaginary parts) must lie inside it, and the
// data of a numeric array must be numbers, exactly as many as its dimensions
// declare. The declared values may need at most the file's bytes (x 1032 when
// compressed: deflate's largest ratio). Sets *name once the name is read.
std::string CheckMatrixContent(const ContentReader& read, std::uint64_t size, bool swap,
                               std::uintmax_t file_bytes, bool compressed, std::string* name,
                               int depth = 0) {
  Tag flags;
  unsigned char f[8];
  if (size < 16 || !ReadTag(read, 0, swap, &flags) || flags.type != kMiUint32 || flags.bytes != 8 ||
      !read(flags.data_at, 8, f)) {
    return "its array flags are missing or damaged";
  }
  const std::uint32_t word = ReadU32(f, swap);
  const std::uint32_t cls = word & 0xFF;
  const bool complex = (word & 0x0800) != 0;
  const std::uint32_t nzmax = ReadU32(f + 4, swap);  // sparse: most non-zero values
  Tag dims_tag;
  if (!ReadTag(read, flags.next, swap, &dims_tag) || dims_tag.type != kMiInt32 ||
      dims_tag.bytes < 8 || dims_tag.bytes % 4 != 0 || dims_tag.bytes > 4 * 32 ||
      dims_tag.data_at + dims_tag.bytes > size) {
    return "its dimensions are missing or damaged";
  }
  unsigned char d[4 * 32];
  if (!read(dims_tag.data_at, static_cast<std::size_t>(dims_tag.bytes), d)) {
    return "its dimensions are missing or damaged";
  }
  std::vector<std::uint32_t> dims;
  std::string dims_text;
  long double count = 1.0L;
  for (std::uint64_t i = 0; i < dims_tag.bytes / 4; ++i) {
    const std::uint32_t v = ReadU32(d + 4 * i, swap);
    if (v > 0x7FFFFFFFu) return "a negative dimension";
    dims.push_back(v);
    dims_text += (i ? "x" : "") + std::to_string(v);
    count *= v;
  }
  Tag name_tag;
  if (!ReadTag(read, dims_tag.next, swap, &name_tag) ||
      (name_tag.type != kMiInt8 && name_tag.type != kMiUint8) || name_tag.bytes > 4096 ||
      name_tag.data_at + name_tag.bytes > size) {
    return "its name is missing or damaged";
  }
  std::string n(static_cast<std::size_t>(name_tag.bytes), '\0');
  if (!n.empty() && !read(name_tag.data_at, n.size(), reinterpret_cast<unsigned char*>(&n[0]))) {
    return "its name is missing or damaged";
  }
  *name = n;
  // The declared values against the file, for every class (matio allocates
  // what the dimensions say before it reads: 6e12 cells of a 776-byte file
  // asked for 48 TB): a number takes its bytes, a cell, struct or object
  // element at least a tag of 8, a character 1; a sparse array its nzmax
  // row indices and its column starts (int32 each).
  const long double room = static_cast<long double>(file_bytes) * (compressed ? 1032.0L : 1.0L);
  long double need = count * 8.0L;
  if (IsNumericClass(cls)) need = count * ClassValueBytes(cls);
  if (cls == 4) need = count;  // char
  if (cls == 5) {              // sparse
    need = std::max(4.0L * nzmax, 4.0L * (dims.size() > 1 ? dims[1] + 1.0L : 1.0L));
  }
  if (need > room + 1024.0L) {
    return (cls == 5 ? "declares a sparse " + dims_text + " array of " + std::to_string(nzmax) +
                           " values"
                     : "declares " + dims_text + " values") +
           ", more than the " + std::to_string(file_bytes) + "-byte file can hold";
  }
  if (IsNumericClass(cls)) {
    std::uint64_t at = name_tag.next;
    for (const char* part : {"its data", "its imaginary part"}) {
      if (part[4] == 'i' && !complex) break;
      Tag data;
      if (at + 8 > size) {
        if (count == 0.0L) break;
        return "declares " + dims_text + " values, but its element ends before " + part;
      }
      if (!ReadTag(read, at, swap, &data)) break;  // not kept (a long compressed name)
      if (data.type == kMiUtf8 || data.type == kMiUtf16 || data.type == kMiUtf32) {
        return std::string("class ") + ArrayClassName(cls) + " declares numbers, but " + part +
               " are text (" + TextTypeName(data.type) + ")";
      }
      const std::size_t bytes = NumericTypeBytes(data.type);
      if (bytes == 0) {
        return std::string(part) + " are of data type " + std::to_string(data.type) +
               ", not numbers";
      }
      if (data.small && data.bytes > 4) {
        return std::string(part) + " are damaged (a small element of over 4 bytes)";
      }
      if (data.data_at + data.bytes > size) {
        return std::string(part) + " (" + std::to_string(data.bytes) +
               " bytes) overrun the variable's element, which ends " +
               std::to_string(size - std::min(size, data.data_at)) + " bytes after their tag";
      }
      if (data.bytes % bytes != 0) {
        return std::string(part) + " (" + std::to_string(data.bytes) +
               " bytes) are not a whole number of " + std::to_string(bytes) + "-byte values";
      }
      const long double values = static_cast<long double>(data.bytes / bytes);
      if (values != count) {
        char text[64];
        std::snprintf(text, sizeof(text), "%.0Lf", values);
        return std::string(part) + " hold " + text + " values, but its dimensions declare " +
               dims_text + (values < count ? " (data cut short?)" : "");
      }
      at = data.next;
    }
  }
  // Every class: each sub-element after the name (a sparse array's indices,
  // a character array's text, a cell's or struct's elements) lies inside the
  // variable's element (matio allocates what a tag declares: 4 GB for a
  // sparse index tag of a 560-byte file), and the variables inside a cell or
  // struct are checked the same way.
  for (std::uint64_t at = name_tag.next; at + 8 <= size;) {
    Tag t;
    if (!ReadTag(read, at, swap, &t)) break;  // not kept (compressed, past the head)
    if ((t.small && t.bytes > 4) || t.data_at + t.bytes > size) {
      return "a part of " + std::to_string(t.bytes) +
             " bytes overruns the variable's element, which ends " +
             std::to_string(size - std::min(size, t.data_at)) + " bytes after its tag";
    }
    if (t.type == kMiMatrix && t.bytes > 0 && depth < 8) {  // 0 bytes: an empty element
      const ContentReader inner = [&read, &t](std::uint64_t off, std::size_t n,
                                              unsigned char* out) {
        return off + n <= t.bytes && read(t.data_at + off, n, out);
      };
      std::string inner_name;
      const std::string problem =
          CheckMatrixContent(inner, t.bytes, swap, file_bytes, compressed, &inner_name, depth + 1);
      if (!problem.empty()) return "an element inside it: " + problem;
    }
    at = t.next;
  }
  return "";
}

// Inflates a miCOMPRESSED element's bytes, keeping the first `keep` bytes of
// the output and counting all of it, up to `limit` bytes (then stops). False
// when the stream is damaged.
bool Inflate(const std::vector<unsigned char>& in, std::size_t keep, std::uint64_t limit,
             std::vector<unsigned char>* head, std::uint64_t* total) {
  z_stream z{};
  if (inflateInit(&z) != Z_OK) return false;
  z.next_in = const_cast<unsigned char*>(in.data());
  z.avail_in = static_cast<uInt>(in.size());
  std::vector<unsigned char> buf(1 << 16);
  *total = 0;
  int rc = Z_OK;
  while (rc == Z_OK && *total <= limit) {
    z.next_out = buf.data();
    z.avail_out = static_cast<uInt>(buf.size());
    rc = inflate(&z, Z_NO_FLUSH);
    const std::size_t got = buf.size() - z.avail_out;
    if (head->size() < keep) {
      head->insert(head->end(), buf.begin(), buf.begin() + std::min(got, keep - head->size()));
    }
    *total += got;
    if (rc == Z_BUF_ERROR && got == 0) break;  // input ended before the stream did
  }
  inflateEnd(&z);
  return rc == Z_STREAM_END || *total > limit;
}

// A MAT v5 file is a 128-byte header and top-level data elements, each an
// 8-byte tag (type, byte count) and its bytes. Every element must end inside
// the file (a file cut short is damaged: matio would read zeros or garbage),
// and every numeric variable must hold numbers, as many as its dimensions
// declare, inside its element (matio read an overrun, short data or text
// where doubles were declared with warnings only). Compressed variables are
// inflated (at most the size their tag declares) and checked the same way.
void CheckMat5Elements(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(path + ": cannot read (no such file or not readable)");
  unsigned char header[128];
  if (std::fread(header, 1, 128, f.get()) != 128) {
    throw InputError(path + ": damaged MATLAB file (shorter than its 128-byte header)");
  }
  const bool swap = header[126] == 'M' && header[127] == 'I';
  const std::uintmax_t size = std::filesystem::file_size(path);
  auto damaged = [&](int element, const std::string& name, const std::string& problem) {
    // "variable 't' declares 2000000000x1 values, ..." as ReadMatTable says it.
    const bool declares = problem.rfind("declares ", 0) == 0;
    throw InputError(path + ": damaged MATLAB file (" +
                     (name.empty() ? "element " + std::to_string(element)
                                   : "variable '" + Excerpt(name, 40) + "'") +
                     (declares ? " " : ": ") + problem + ")");
  };
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
    const std::uintmax_t declared = bytes;
    if (type != kMiCompressed) bytes = (bytes + 7) / 8 * 8;  // miCOMPRESSED is not padded
    const std::uintmax_t end = pos + 8 + bytes;
    if (end > size) {
      throw InputError(path + ": damaged MATLAB file (element " + std::to_string(element) +
                       " declares " + std::to_string(bytes) + " bytes, but the file ends " +
                       std::to_string(size - pos - 8) + " bytes after its tag: truncated?)");
    }
    const std::uintmax_t content_at = pos + 8;
    pos = end;  // the next element, whatever this one holds
    std::string name;
    if (type == kMiMatrix) {
      const ContentReader read = [&](std::uint64_t off, std::size_t n, unsigned char* out) {
        return off + n <= declared &&
               std::fseek(f.get(), static_cast<long>(content_at + off), SEEK_SET) == 0 &&
               std::fread(out, 1, n, f.get()) == n;
      };
      const std::string problem = CheckMatrixContent(read, declared, swap, size, false, &name);
      if (!problem.empty()) damaged(element, name, problem);
    } else if (type == kMiCompressed) {
      std::vector<unsigned char> in(static_cast<std::size_t>(declared));
      if (std::fseek(f.get(), static_cast<long>(content_at), SEEK_SET) != 0 ||
          std::fread(in.data(), 1, in.size(), f.get()) != in.size()) {
        damaged(element, "", "cannot read its compressed bytes");
      }
      // The inner tag first: what it declares bounds the inflation (zlib
      // packs at most 1032:1).
      std::vector<unsigned char> head;
      std::uint64_t total = 0;
      Inflate(in, 8, 8, &head, &total);
      if (head.size() < 8) damaged(element, "", "its compressed data do not inflate");
      const std::uint32_t inner_type = ReadU32(head.data(), swap);
      const std::uint64_t inner = ReadU32(head.data() + 4, swap);
      if (inner_type != kMiMatrix) {  // a compressed element holds one variable
        damaged(element, "",
                "its compressed data hold data type " + std::to_string(inner_type) +
                    ", not a variable (miMATRIX, 14)");
      }
      const long double room = static_cast<long double>(in.size()) * 1032.0L + 1024.0L;
      if (static_cast<long double>(inner) > room) {
        damaged(element, "",
                "its compressed variable declares " + std::to_string(inner) + " bytes, more than " +
                    std::to_string(in.size()) + " compressed bytes can hold");
      }
      head.clear();
      const std::size_t keep =
          static_cast<std::size_t>(std::min<std::uint64_t>(inner + 8, 1 << 16));
      if (!Inflate(in, keep, inner + 8, &head, &total)) {
        damaged(element, "", "its compressed data are damaged (zlib)");
      }
      const ContentReader read = [&](std::uint64_t off, std::size_t n, unsigned char* out) {
        if (off + n > inner || 8 + off + n > head.size()) return false;
        std::memcpy(out, head.data() + 8 + off, n);
        return true;
      };
      const std::string problem = CheckMatrixContent(read, inner, swap, size, true, &name);
      if (!problem.empty()) damaged(element, name, problem);
      if (total < inner + 8) {
        damaged(element, name,
                "its compressed data inflate to " + std::to_string(total) +
                    " bytes, but its element declares " + std::to_string(inner + 8) +
                    " (cut short?)");
      }
    }
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

// A MAT v5 or v7.3 file starts with a 128-byte header: descriptive text, the
// version 0x0100 (0x0200 for v7.3) and the endian indicator "IM" (or "MI"
// when written on a machine of the other byte order). Anything else matio
// tries as MAT v4, which has no header and trusts the name length it reads
// first (a fuzzer's 305-byte file made it allocate 1.7 GB): refused here.
void CheckMatHeader(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(path + ": cannot read (no such file or not readable)");
  unsigned char header[128];
  const bool full = std::fread(header, 1, 128, f.get()) == 128;
  const bool le = full && header[126] == 'I' && header[127] == 'M';
  const bool be = full && header[126] == 'M' && header[127] == 'I';
  const unsigned version = le ? header[124] | header[125] << 8 : header[124] << 8 | header[125];
  if (!(le || be) || (version != 0x0100 && version != 0x0200)) {
    throw InputError(path +
                     ": not a MATLAB v5/v7 file (no 128-byte MAT-file header with its version and "
                     "byte order; MAT v4 files are not read: save with -v7)");
  }
}

}  // namespace

DataTable ReadMatTable(const std::string& path, const std::vector<std::string>& wanted) {
  CheckInputFile(path);
  CheckMatHeader(path);
  MatFile mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY), &Mat_Close);
  if (!mat) throw InputError(path + ": not a MATLAB file that matio can read");
  const bool v73 = Mat_GetVersion(mat.get()) == MAT_FT_MAT73;
  if (Mat_GetVersion(mat.get()) == MAT_FT_MAT5) CheckMat5Elements(path);
  const std::uintmax_t file_bytes = std::filesystem::file_size(path);
  DataTable table;
  table.path = path;
  table.is_mat = true;
  std::size_t n_vars = 0;
  if (char** dir = Mat_GetDir(mat.get(), &n_vars)) {
    for (std::size_t i = 0; i < n_vars; ++i) table.names.push_back(dir[i]);
  }
  // A v7.3 file HDF5 cannot open (cut short, say) shows no variable at all.
  if (v73 && table.names.empty()) {
    throw InputError(path +
                     ": damaged MATLAB file (a v7.3 file in which matio finds no variable: HDF5 "
                     "cannot read it, cut short?)");
  }
  std::string first;  // the first variable read, for length messages
  for (const std::string& name : wanted) {
    if (table.columns.count(name)) continue;
    const bool listed =
        std::find(table.names.begin(), table.names.end(), name) != table.names.end();
    matio_classes class_type = MAT_C_EMPTY;
    {  // declared size against the file size before reading (deflate packs <= 1032:1)
      MatVar info(Mat_VarReadInfo(mat.get(), name.c_str()), &Mat_VarFree);
      if (!info) {
        if (listed) {
          throw InputError(path + ": damaged MATLAB file (variable '" + name +
                           "': listed, but matio cannot read its header)");
        }
        continue;
      }
      class_type = info->class_type;
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
    if (!var) {  // its header was read: a class matio does not read, or damaged data
      if (!IsNumericClass(static_cast<std::uint32_t>(class_type))) {
        throw InputError(path + ": variable '" + name + "': not numeric (class " +
                         ClassName(class_type) + ")");
      }
      throw InputError(path + ": damaged MATLAB file (variable '" + name +
                       "': matio cannot read its data)");
    }
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

void SilenceMatioDiagnostics() { Mat_LogClose(); }

}  // namespace triadcal
