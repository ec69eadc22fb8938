// Reader of MATLAB files through matio: the wanted variables, each a real
// numeric vector, converted to double.
#include <matio.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>

#include "core/io/data_table.h"
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

}  // namespace

DataTable ReadMatTable(const std::string& path, const std::vector<std::string>& wanted) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(path + ": cannot read (no such file or not readable)");
  }
  MatFile mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY), &Mat_Close);
  if (!mat) throw InputError(path + ": not a MATLAB file that matio can read");
  DataTable table;
  table.path = path;
  table.is_mat = true;
  std::size_t n_vars = 0;
  if (char** dir = Mat_GetDir(mat.get(), &n_vars)) {
    for (std::size_t i = 0; i < n_vars; ++i) table.names.push_back(dir[i]);
  }
  std::string first;  // the first variable read, for length messages
  for (const std::string& name : wanted) {
    if (table.columns.count(name)) continue;
    MatVar var(Mat_VarRead(mat.get(), name.c_str()), &Mat_VarFree);
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
