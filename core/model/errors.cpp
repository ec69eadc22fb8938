// One-line error text.
#include "core/model/errors.h"

#include <algorithm>
#include <cstdio>

namespace triadcal {

std::string OneLine(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02X", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out;
}

std::string Excerpt(const std::string& text, std::size_t max_chars) {
  max_chars = std::max<std::size_t>(max_chars, 24);
  if (text.size() <= max_chars) {
    const std::string escaped = OneLine(text);
    if (escaped.size() <= max_chars) return escaped;
  }
  // Escaping may lengthen the text (\xNN for one byte): cut the raw bytes so
  // that the escaped excerpt stays within the bound.
  const std::size_t head = max_chars - 20, tail = 12;
  std::string front = OneLine(text.substr(0, head));
  if (front.size() > head) front.resize(head);
  std::string back = OneLine(text.substr(text.size() - std::min(tail, text.size())));
  if (back.size() > tail) back = back.substr(back.size() - tail);
  return front + "..." + back;
}

}  // namespace triadcal
