// Allocation-free token and number scanning over one line of text, for the
// text model formats (OBJ, MTL, ASCII PLY, OFF, ASCII STL). Numbers use
// std::from_chars (locale-independent); a leading '+' is accepted.
#pragma once

#include <charconv>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace cellbake {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// A cursor over one line; every read skips leading blanks first.
struct TextScan {
  const char* p;
  const char* end;

  explicit TextScan(std::string_view line) : p(line.data()), end(line.data() + line.size()) {}

  void skip_blanks() {
    while (p < end && is_blank(*p)) ++p;
  }
  // True when nothing but blanks remains.
  bool at_end() {
    skip_blanks();
    return p == end;
  }
  // Next blank-separated token; empty at the end of the line.
  std::string_view token() {
    skip_blanks();
    const char* start = p;
    while (p < end && !is_blank(*p)) ++p;
    return {start, static_cast<std::size_t>(p - start)};
  }
  // The rest of the line without surrounding blanks.
  std::string_view rest() {
    skip_blanks();
    const char* last = end;
    while (last > p && is_blank(last[-1])) --last;
    std::string_view r(p, static_cast<std::size_t>(last - p));
    p = end;
    return r;
  }
  // Parses a whole blank-terminated number token ("nan"/"inf" are parsed too;
  // callers check finiteness). Returns false, leaving the cursor at the token,
  // when the token is missing or not entirely a number.
  bool number(double& out) {
    skip_blanks();
    const char* start = p;
    if (start < end && *start == '+') ++start;
    const auto [next, ec] = std::from_chars(start, end, out);
    if (ec != std::errc() || (next < end && !is_blank(*next))) return false;
    p = next;
    return true;
  }
  // Parses a signed integer that may be followed by any character (e.g. the
  // '/' of an OBJ face corner). Returns false when no digits are present.
  bool integer_prefix(std::int64_t& out) {
    const char* start = p;
    if (start < end && *start == '+') ++start;
    const auto [next, ec] = std::from_chars(start, end, out);
    if (ec != std::errc()) return false;
    p = next;
    return true;
  }
  // Parses a whole blank-terminated integer token.
  bool integer(std::int64_t& out) {
    skip_blanks();
    const char* save = p;
    if (!integer_prefix(out) || (p < end && !is_blank(*p))) {
      p = save;
      return false;
    }
    return true;
  }
};

// Case-sensitive keyword test used for line dispatch.
inline bool starts_with_word(std::string_view line, std::string_view word) {
  return line.size() >= word.size() && line.substr(0, word.size()) == word &&
         (line.size() == word.size() || is_blank(line[word.size()]));
}

}  // namespace cellbake
