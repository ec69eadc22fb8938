// Raw numeric columns read from a data file, before any mapping or checking:
// the CSV / whitespace text reader and the MATLAB reader both produce one.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace triadcal {

// At most this many columns in a text file's header (or data_format.header):
// a run file has a few dozen; a header line of a million names is a binary
// file or a damaged one (and each name costs memory for every row).
constexpr std::size_t kMaxColumns = 10000;

struct DataTable {
  std::string path;
  bool is_mat = false;
  std::vector<std::string> names;  // every column (header) or variable in the file
  int header_line = 0;             // text: 1-based line of the header
  std::map<std::string, std::vector<double>> columns;  // the wanted ones found
  // Text columns asked for with TextTableOptions::wanted_text (e.g. position labels).
  std::map<std::string, std::vector<std::string>> text_columns;
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

// What a text file may need beyond the CSV contract (run.yaml `data_format`
// and `columns.label`).
struct TextTableOptions {
  // The column names, in order, of a file without a header line: every
  // non-comment line is then data. Empty: the first such line is the header.
  std::vector<std::string> header;
  // Columns kept as text instead of parsed as numbers (a position label).
  std::vector<std::string> wanted_text;
  // 1: the lines are parsed on the calling thread alone; else large blocks
  // on two threads when the machine has two cores (the same table).
  int threads = 0;
};
DataTable ReadTextTable(const std::string& path, const std::vector<std::string>& wanted,
                        const TextTableOptions& options);

// Reads the wanted variables of a MATLAB file (matio: v5, and v7.3 when matio
// has HDF5). Each must be a real numeric vector (row or column) with the
// length of the others. Missing variables are left out of `columns`. A
// damaged file gives InputError("PATH: damaged MATLAB file (WHAT)"), WHAT
// from the reader's own checks (the element or variable, and what is wrong):
// matio's log has no place for the caller's state, so its messages are not
// quoted.
DataTable ReadMatTable(const std::string& path, const std::vector<std::string>& wanted);

// Turns off what matio and the HDF5 library under it print on stderr (HDF5
// prints a stack of errors for a damaged v7.3 file; matio 1.5 prints nothing
// unless asked). Settings of those libraries for the whole process: call it
// once, before reading, from the program (tools/main.cpp, the Python module);
// a library caller that does not call it reads the same and gets the same
// errors, with HDF5's report on stderr besides.
void SilenceMatioDiagnostics();

}  // namespace triadcal
