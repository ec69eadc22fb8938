// Fast reader of the text form of run data (CSV contract of docs/file-formats.md, or
// blank-separated text): one pass over the file in blocks, numbers parsed with
// std::from_chars, only the wanted columns converted.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <thread>
#include <unordered_map>

#include "core/io/data_table.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {

// The last '\n' of [begin, end), or null (a line is short: a backward scan).
const char* LastLineEnd(const char* begin, const char* end) {
  while (end != begin) {
    if (*--end == '\n') return end;
  }
  return nullptr;
}

// The lines of a file, read in blocks: memory stays at one block however long
// the file (a 40-min 1-kHz run is 250 MB of text). A line is valid until the
// next call.
class LineSource {
 public:
  explicit LineSource(const std::string& path) : path_(path), f_(nullptr, &std::fclose) {
    CheckInputFile(path);
    f_.reset(std::fopen(path.c_str(), "rb"));
    if (!f_) throw InputError(path + ": cannot read (no such file or not readable)");
    if (std::fseek(f_.get(), 0, SEEK_END) == 0) {
      const long size = std::ftell(f_.get());
      if (size > 0) size_ = static_cast<std::size_t>(size);
      std::fseek(f_.get(), 0, SEEK_SET);
    }
    // A small file in one read of its size (+1 to see its end), not a block.
    if (size_ > 0 && size_ < kBlock) block_ = size_ + 1;
    Fill();
    if (end_ - begin_ >= 3 && std::memcmp(buf_.data(), "\xEF\xBB\xBF", 3) == 0) begin_ += 3;
  }

  // The next line without its '\n'; false at the end of the file.
  bool Next(const char** line_begin, const char** line_end) {
    for (;;) {
      const char* p = buf_.data() + begin_;
      const char* end = buf_.data() + end_;
      if (const char* eol = static_cast<const char*>(std::memchr(p, '\n', end - p))) {
        *line_begin = p;
        *line_end = eol;
        begin_ = static_cast<std::size_t>(eol + 1 - buf_.data());
        return true;
      }
      if (eof_) {
        if (p == end) return false;
        *line_begin = p;
        *line_end = end;
        begin_ = end_;
        return true;
      }
      Fill();
    }
  }

  // The complete lines the buffer holds (at least one, each with its '\n';
  // the last line of the file may lack it); false at the end of the file.
  // Valid until the next call.
  bool NextLines(const char** begin, const char** end) {
    for (;;) {
      const char* p = buf_.data() + begin_;
      const std::size_t n = end_ - begin_;
      if (const char* eol = LastLineEnd(p, p + n)) {
        *begin = p;
        *end = eol + 1;
        begin_ = static_cast<std::size_t>(eol + 1 - buf_.data());
        return true;
      }
      if (eof_) {
        if (n == 0) return false;
        *begin = p;
        *end = p + n;
        begin_ = end_;
        return true;
      }
      Fill();
    }
  }

  // About how many lines the file has, from the first block's.
  std::size_t LinesEstimate() const {
    const std::size_t in_block = static_cast<std::size_t>(
        std::count(buf_.data() + begin_, buf_.data() + end_, '\n'));
    if (eof_ || in_block == 0) return in_block + 1;
    return static_cast<std::size_t>(static_cast<double>(in_block) *
                                     static_cast<double>(size_) /
                                     static_cast<double>(end_ - begin_)) + 1;
  }

 private:
  static constexpr std::size_t kBlock = 1 << 22;

  // Keeps the unread part, then reads the next block behind it (the buffer
  // grows only for a line longer than a block).
  void Fill() {
    std::memmove(&buf_[0], buf_.data() + begin_, end_ - begin_);  // the unread part only
    end_ -= begin_;
    begin_ = 0;
    if (buf_.size() < end_ + block_) buf_.resize(end_ + block_);
    const std::size_t n = std::fread(&buf_[end_], 1, buf_.size() - end_, f_.get());
    if (std::ferror(f_.get())) throw InputError(path_ + ": read error");
    end_ += n;
    if (n == 0 || std::feof(f_.get())) eof_ = true;
  }

  std::string path_;
  std::unique_ptr<FILE, int (*)(FILE*)> f_;
  std::string buf_;
  std::size_t begin_ = 0, end_ = 0;  // the unread bytes [begin_, end_) of buf_
  std::size_t size_ = 0;
  std::size_t block_ = kBlock;
  bool eof_ = false;
};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// [begin, end) of the next field starting at p; returns the position after the
// separator (or end of line).
struct Field {
  const char* begin;
  const char* end;
};

class LineSplitter {
 public:
  LineSplitter(const char* begin, const char* end, bool comma)
      : p_(begin), end_(end), comma_(comma) {
    if (!comma_) SkipBlanks();
  }
  bool Next(Field* f) {
    if (comma_) {
      if (done_) return false;
      const char* sep = p_;  // fields are short: a plain loop beats memchr
      while (sep != end_ && *sep != ',') ++sep;
      f->begin = p_;
      f->end = sep;
      if (sep != end_) {
        p_ = sep + 1;
      } else {
        done_ = true;
      }
    } else {
      if (p_ == end_) return false;
      f->begin = p_;
      while (p_ != end_ && !IsBlank(*p_)) ++p_;
      f->end = p_;
      SkipBlanks();
    }
    while (f->begin != f->end && IsBlank(*f->begin)) ++f->begin;
    while (f->end != f->begin && IsBlank(f->end[-1])) --f->end;
    return true;
  }

 private:
  void SkipBlanks() {
    while (p_ != end_ && IsBlank(*p_)) ++p_;
  }
  const char* p_;
  const char* end_;
  bool comma_;
  bool done_ = false;
};

std::string HeaderName(Field f) {
  std::string s(f.begin, f.end);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) {
    s = s.substr(1, s.size() - 2);
  }
  return s;
}

bool IsSkippedLine(const char* b, const char* e) {
  while (b != e && IsBlank(*b)) ++b;
  return b == e || *b == '#';
}

}  // namespace

std::string DataTable::Where(std::size_t row) const {
  if (is_mat) return path + ": sample " + std::to_string(row + 1);
  return path + ":" + std::to_string(line[row]);
}

DataTable ReadTextTable(const std::string& path, const std::vector<std::string>& wanted) {
  return ReadTextTable(path, wanted, TextTableOptions{});
}

namespace {

// How the data lines are read, once the column names are known: which fields
// are wanted (as numbers or as text), and what a message names.
struct DataLineFormat {
  std::string path;
  bool comma = true;
  std::size_t fields_needed = 0;  // the last wanted field + 1
  std::vector<char> number, text;  // per field: wanted as a number, as text
  const std::vector<std::string>* names = nullptr;
  bool header_given = false;  // data_format.header names the columns
  int header_line = 0;
};

// The wanted fields of a stretch of data lines, per field, and each row's
// file line.
struct ParsedRows {
  std::vector<std::vector<double>> number;
  std::vector<std::vector<std::string>> text;
  std::vector<int> line;
  void Clear(std::size_t fields) {
    number.resize(fields);
    text.resize(fields);
    for (std::vector<double>& v : number) v.clear();
    for (std::vector<std::string>& v : text) v.clear();
    line.clear();
  }
};

// One data line (file line line_no) into out; throws InputError naming the line.
void ParseDataLine(const DataLineFormat& f, const char* line_begin, const char* line_end,
                   int line_no, ParsedRows* out) {
  const std::vector<std::string>& names = *f.names;
  auto where = [&] { return f.path + ":" + std::to_string(line_no) + ": "; };
  LineSplitter split(line_begin, line_end, f.comma);
  Field fd;
  std::size_t idx = 0;
  for (; idx < f.fields_needed && split.Next(&fd); ++idx) {
    if (f.text[idx]) {
      out->text[idx].push_back(HeaderName(fd));  // unquoted like a header name
      continue;
    }
    if (!f.number[idx]) continue;
    const char* b = fd.begin;
    if (b != fd.end && *b == '+') ++b;
    double v = 0.0;
    const auto res = std::from_chars(b, fd.end, v);
    if (res.ec == std::errc::result_out_of_range) {
      v = std::strtod(std::string(fd.begin, fd.end).c_str(), nullptr);  // +-inf or denormal
    } else if (res.ec != std::errc() || res.ptr != fd.end || fd.begin == fd.end) {
      throw InputError(where() + "column '" + Excerpt(names[idx]) + "': not a number: '" +
                       Excerpt(std::string(fd.begin, fd.end)) + "'");
    }
    out->number[idx].push_back(v);
  }
  if (idx == f.fields_needed) {  // strict rows: count the fields not read
    while (split.Next(&fd)) ++idx;
  }
  if (idx < f.fields_needed) {
    std::size_t missing = idx;
    while (!f.number[missing] && !f.text[missing]) ++missing;
    throw InputError(where() + std::to_string(idx) + " fields, but column '" +
                     Excerpt(names[missing]) + "' is field " + std::to_string(missing + 1) +
                     (f.header_given ? " of data_format.header" : " of the header"));
  }
  if (idx != names.size()) {
    throw InputError(where() + std::to_string(idx) + " fields, but the " +
                     (f.header_given ? std::string("data_format.header")
                                     : "header (line " + std::to_string(f.header_line) + ")") +
                     " has " + std::to_string(names.size()) +
                     (f.comma && idx > names.size() ? " (a decimal comma?)" : ""));
  }
  out->line.push_back(line_no);
}

// The lines of [begin, end), the first being file line first_line (comment
// and blank lines skipped). Returns the number of line ends in [begin, end).
// A line that fails throws its InputError; with `failed`, its text and line
// are kept there first (a part numbered from 0: ParseBlock).
struct FailedLine {
  const char* begin = nullptr;
  const char* end = nullptr;
  int line_no = 0;
};
int ParseDataLines(const DataLineFormat& f, const char* begin, const char* end, int first_line,
                   ParsedRows* out, FailedLine* failed = nullptr) {
  int line_no = first_line;
  while (begin != end) {
    const char* eol = static_cast<const char*>(std::memchr(begin, '\n', end - begin));
    const char* line_end = eol ? eol : end;
    if (!IsSkippedLine(begin, line_end)) {
      if (failed) *failed = {begin, line_end, line_no};
      ParseDataLine(f, begin, line_end, line_no, out);
    }
    if (!eol) break;
    ++line_no;
    begin = eol + 1;
  }
  return line_no - first_line;
}

// Below this many bytes the lines the reader holds are parsed on one thread.
constexpr std::size_t kMinSplit = 1 << 16;

// A block of data lines parsed on two threads, split at a line end near its
// middle. Neither part waits for the other: the second is numbered from line
// 0, and once both are done its rows' lines are moved by the first part's
// line ends (counted before splitting, and after, they kept one thread
// waiting for the other at every block). An error in the first part is the
// one reported (the earlier line); one in the second only is raised again
// from its line, numbered in the file. Returns the number of line ends in
// [begin, end).
// threads: TextTableOptions::threads (1: no second thread).
int ParseBlock(const DataLineFormat& f, const char* begin, const char* end, int first_line,
               int threads, ParsedRows* first, ParsedRows* second) {
  const std::size_t fields = f.number.size();
  first->Clear(fields);
  second->Clear(fields);
  const char* mid = begin + (end - begin) / 2;
  const char* split = static_cast<const char*>(std::memchr(mid, '\n', end - mid));
  if (end - begin < static_cast<std::ptrdiff_t>(kMinSplit) || !split || threads == 1 ||
      std::thread::hardware_concurrency() < 2) {
    return ParseDataLines(f, begin, end, first_line, first);
  }
  ++split;  // after the line end
  std::exception_ptr second_error;
  FailedLine second_failed;
  int second_lines = 0;
  std::thread worker([&] {
    try {
      second_lines = ParseDataLines(f, split, end, 0, second, &second_failed);
    } catch (...) {
      second_error = std::current_exception();
    }
  });
  std::exception_ptr first_error;
  int first_lines = 0;
  try {
    first_lines = ParseDataLines(f, begin, split, first_line, first);
  } catch (...) {
    first_error = std::current_exception();
  }
  worker.join();
  if (first_error) std::rethrow_exception(first_error);
  const int offset = first_line + first_lines;
  if (second_error) {
    ParsedRows scratch;
    scratch.Clear(fields);
    ParseDataLine(f, second_failed.begin, second_failed.end, offset + second_failed.line_no,
                  &scratch);
    std::rethrow_exception(second_error);  // not reached: the line fails again
  }
  for (int& line : second->line) line += offset;
  return first_lines + second_lines;
}

// The header line's column names; throws InputError for a name given twice
// or too many names.
std::vector<std::string> HeaderNames(const std::string& path, const char* line_begin,
                                     const char* line_end, bool comma, int line_no) {
  std::vector<std::string> names;
  LineSplitter split(line_begin, line_end, comma);
  Field f;
  // Linear in the number of names (a search per name was quadratic:
  // 80 000 names took 8 s, a million never ended).
  std::unordered_map<std::string, std::size_t> field_of_name;
  while (split.Next(&f)) {
    if (names.size() == kMaxColumns) {
      throw InputError(path + ":" + std::to_string(line_no) + ": the header has more than " +
                       std::to_string(kMaxColumns) +
                       " columns (bound: a run file has a few dozen; is this a data file?)");
    }
    const std::string name = HeaderName(f);
    const auto [seen, inserted] = field_of_name.emplace(name, names.size());
    if (!inserted && !name.empty()) {
      throw InputError(path + ":" + std::to_string(line_no) + ": column '" + Excerpt(name) +
                       "' appears twice (fields " + std::to_string(seen->second + 1) + " and " +
                       std::to_string(names.size() + 1) +
                       "); rename one, or name the columns with data_format.header");
    }
    names.push_back(name);
  }
  return names;
}

}  // namespace

DataTable ReadTextTable(const std::string& path, const std::vector<std::string>& wanted,
                        const TextTableOptions& options) {
  LineSource lines(path);  // without a UTF-8 BOM
  DataTable table;
  table.path = path;
  DataLineFormat format;
  format.path = path;
  format.header_given = !options.header.empty();
  const std::size_t rows_estimate = lines.LinesEstimate();

  // 1. The column names: the first line that is not a comment or blank is
  // the header (or, with data_format.header, the first data line).
  int line_no = 0;
  const char* line_begin = nullptr;
  const char* line_end = nullptr;
  bool first_is_data = false;
  for (;;) {
    if (!lines.Next(&line_begin, &line_end)) {
      throw InputError(path + (options.header.empty() ? ": no header line (the file is empty)"
                                                      : ": no data lines (the file is empty)"));
    }
    ++line_no;
    if (!IsSkippedLine(line_begin, line_end)) break;
  }
  format.comma = std::memchr(line_begin, ',', line_end - line_begin) != nullptr;
  table.header_line = line_no;
  format.header_line = line_no;
  if (options.header.empty()) {
    table.names = HeaderNames(path, line_begin, line_end, format.comma, line_no);
  } else {
    table.names = options.header;
    first_is_data = true;
  }
  format.names = &table.names;

  // 2. Which field feeds which wanted column.
  std::vector<std::vector<double>*> target(table.names.size(), nullptr);
  std::vector<std::vector<std::string>*> text_target(table.names.size(), nullptr);
  auto field_of = [&](const std::string& w) -> std::ptrdiff_t {
    auto it = std::find(table.names.begin(), table.names.end(), w);
    if (it == table.names.end()) return -1;
    const std::size_t idx = static_cast<std::size_t>(it - table.names.begin());
    if (target[idx] || text_target[idx]) return -1;  // asked for twice
    return static_cast<std::ptrdiff_t>(idx);
  };
  for (const std::string& w : options.wanted_text) {
    const std::ptrdiff_t idx = field_of(w);
    if (idx < 0) continue;
    std::vector<std::string>& col = table.text_columns[w];
    col.reserve(rows_estimate);
    text_target[idx] = &col;
    format.fields_needed = std::max(format.fields_needed, static_cast<std::size_t>(idx) + 1);
  }
  for (const std::string& w : wanted) {
    const std::ptrdiff_t idx = field_of(w);
    if (idx < 0) continue;
    std::vector<double>& col = table.columns[w];
    col.reserve(rows_estimate);
    target[idx] = &col;
    format.fields_needed = std::max(format.fields_needed, static_cast<std::size_t>(idx) + 1);
  }
  table.line.reserve(rows_estimate);
  format.number.assign(format.fields_needed, 0);
  format.text.assign(format.fields_needed, 0);
  for (std::size_t idx = 0; idx < format.fields_needed; ++idx) {
    format.number[idx] = target[idx] != nullptr;
    format.text[idx] = text_target[idx] != nullptr;
  }

  // 3. The data lines, block by block, each block's rows appended in order.
  ParsedRows parts[2];
  auto append = [&](const ParsedRows& rows) {
    for (std::size_t idx = 0; idx < format.fields_needed; ++idx) {
      if (target[idx]) {
        target[idx]->insert(target[idx]->end(), rows.number[idx].begin(), rows.number[idx].end());
      }
      if (text_target[idx]) {
        for (const std::string& v : rows.text[idx]) text_target[idx]->push_back(v);
      }
    }
    table.line.insert(table.line.end(), rows.line.begin(), rows.line.end());
  };
  if (first_is_data) {
    parts[0].Clear(format.fields_needed);
    ParseDataLine(format, line_begin, line_end, line_no, &parts[0]);
    append(parts[0]);
  }
  ++line_no;  // the first line of the next block
  const char* block_begin;
  const char* block_end;
  while (lines.NextLines(&block_begin, &block_end)) {
    line_no += ParseBlock(format, block_begin, block_end, line_no, options.threads, &parts[0],
                          &parts[1]);
    append(parts[0]);
    append(parts[1]);
  }
  table.rows = table.line.size();
  return table;
}

}  // namespace triadcal
