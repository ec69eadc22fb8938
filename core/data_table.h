// Raw numeric columns read from a data file, before any mapping or checking:
// the CSV / whitespace text reader and the MATLAB reader both produce one.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace triadcal {

struct DataTable {
  std::string path;
  bool is_mat = false;
  std::vector<std::string> names;  // every column (header) or variable in the file
  int header_line = 0;             // text: 1-based line of the header
  std::map<std::string, std::vector<double>> columns;  // the wanted ones found
  std::vector<int> line;                               // text: 1-based file line of each row
  std::size_t rows = 0;

  bool has(const std::string& name) const { return columns.count(name) > 0; }
  // "FILE:LINE" for text, "FILE: sample N" (1-based) for MAT.
  std::string Where(std::size_t row) const;
};

// Reads the wanted columns of a text file: `#` lines are comments, blank lines
// are skipped, the first other line is the header; fields are separated by
// commas when the header has one, by blanks otherwise. Throws InputError
// ("FILE:LINE: column 'X': not a number: 'abc'", too few fields, no header).
// NaN and Inf are read as such (the caller decides).
DataTable ReadTextTable(const std::string& path, const std::vector<std::string>& wanted);

// Reads the wanted variables of a MATLAB file (matio: v5, and v7.3 when matio
// has HDF5). Each must be a real numeric vector (row or column) with the
// length of the others. Missing variables are left out of `columns`.
DataTable ReadMatTable(const std::string& path, const std::vector<std::string>& wanted);

}  // namespace triadcal
