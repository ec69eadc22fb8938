// Fast reader of the text form of run data (CSV contract of docs/file-formats.md, or
// blank-separated text): one pass over the file in blocks, numbers parsed with
// std::from_chars, only the wanted columns converted.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <unordered_map>

#include "core/io/data_table.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {

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

DataTable ReadTextTable(const std::string& path, const std::vector<std::string>& wanted,
                        const TextTableOptions& options) {
  LineSource lines(path);  // without a UTF-8 BOM
  DataTable table;
  table.path = path;

  int line_no = 0;
  bool comma = true;
  bool have_names = false;
  std::vector<std::vector<double>*> target;  // per field: where its value goes
  std::vector<std::vector<std::string>*> text_target;  // per field, for text columns
  std::size_t fields_needed = 0;
  const std::size_t rows_estimate = lines.LinesEstimate();

  // Once the column names are known: which field feeds which wanted column.
  auto assign_targets = [&]() {
    target.assign(table.names.size(), nullptr);
    text_target.assign(table.names.size(), nullptr);
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
      fields_needed = std::max(fields_needed, static_cast<std::size_t>(idx) + 1);
    }
    for (const std::string& w : wanted) {
      const std::ptrdiff_t idx = field_of(w);
      if (idx < 0) continue;
      std::vector<double>& col = table.columns[w];
      col.reserve(rows_estimate);
      target[idx] = &col;
      fields_needed = std::max(fields_needed, static_cast<std::size_t>(idx) + 1);
    }
    table.line.reserve(rows_estimate);
    have_names = true;
  };

  const char* line_begin;
  const char* line_end;
  while (lines.Next(&line_begin, &line_end)) {
    ++line_no;
    if (IsSkippedLine(line_begin, line_end)) continue;

    if (!have_names) {
      comma = std::memchr(line_begin, ',', line_end - line_begin) != nullptr;
      table.header_line = line_no;
      if (options.header.empty()) {  // this line is the header
        LineSplitter split(line_begin, line_end, comma);
        Field f;
        // Linear in the number of names (a search per name was quadratic:
        // 80 000 names took 8 s, a million never ended).
        std::unordered_map<std::string, std::size_t> field_of_name;
        while (split.Next(&f)) {
          if (table.names.size() == kMaxColumns) {
            throw InputError(path + ":" + std::to_string(line_no) + ": the header has more than " +
                             std::to_string(kMaxColumns) +
                             " columns (bound: a run file has a few dozen; is this a data file?)");
          }
          const std::string name = HeaderName(f);
          const auto [seen, inserted] = field_of_name.emplace(name, table.names.size());
          if (!inserted && !name.empty()) {
            throw InputError(path + ":" + std::to_string(line_no) + ": column '" + Excerpt(name) +
                             "' appears twice (fields " + std::to_string(seen->second + 1) +
                             " and " + std::to_string(table.names.size() + 1) +
                             "); rename one, or name the columns with data_format.header");
          }
          table.names.push_back(name);
        }
        assign_targets();
        continue;
      }
      table.names = options.header;  // no header line: this line is data
      assign_targets();
    }

    LineSplitter split(line_begin, line_end, comma);
    Field f;
    std::size_t idx = 0;
    for (; idx < fields_needed && split.Next(&f); ++idx) {
      if (text_target[idx]) {
        text_target[idx]->push_back(HeaderName(f));  // unquoted like a header name
        continue;
      }
      if (!target[idx]) continue;
      const char* b = f.begin;
      if (b != f.end && *b == '+') ++b;
      double v = 0.0;
      const auto res = std::from_chars(b, f.end, v);
      if (res.ec == std::errc::result_out_of_range) {
        v = std::strtod(std::string(f.begin, f.end).c_str(), nullptr);  // +-inf or denormal
      } else if (res.ec != std::errc() || res.ptr != f.end || f.begin == f.end) {
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" +
                         Excerpt(table.names[idx]) + "': not a number: '" +
                         Excerpt(std::string(f.begin, f.end)) + "'");
      }
      target[idx]->push_back(v);
    }
    if (idx == fields_needed) {  // strict rows: count the fields not read
      while (split.Next(&f)) ++idx;
    }
    if (idx < fields_needed) {
      std::size_t missing = idx;
      while (!target[missing] && !text_target[missing]) ++missing;
      throw InputError(path + ":" + std::to_string(line_no) + ": " + std::to_string(idx) +
                       " fields, but column '" + Excerpt(table.names[missing]) + "' is field " +
                       std::to_string(missing + 1) +
                       (options.header.empty() ? " of the header" : " of data_format.header"));
    }
    if (idx != table.names.size()) {
      throw InputError(path + ":" + std::to_string(line_no) + ": " + std::to_string(idx) +
                       " fields, but the " +
                       (options.header.empty() ? "header (line " + std::to_string(table.header_line) + ")"
                                               : std::string("data_format.header")) +
                       " has " + std::to_string(table.names.size()) +
                       (comma && idx > table.names.size() ? " (a decimal comma?)" : ""));
    }
    table.line.push_back(line_no);
  }
  if (!have_names) {
    throw InputError(path + (options.header.empty() ? ": no header line (the file is empty)"
                                                    : ": no data lines (the file is empty)"));
  }
  table.rows = table.line.size();
  return table;
}

}  // namespace triadcal
