#include "pipeline/readers/directx_nesting.h"

#include "pipeline/input_error.h"
#include "pipeline/readers/markup_nesting.h"
#include "pipeline/readers/piecewise_scan.h"

namespace cellbake {

void DirectXNestingScan::feed(const char* data, std::size_t size) {
  std::size_t i = 0;
  while (!decided() && i < size) {
    header_.push_back(data[i++]);
    ++offset_;
    // "xof " + version (4) + format (4) + float size (4)
    if (decided()) text_ = header_.compare(0, 4, "xof ") == 0 && header_.compare(8, 4, "txt ") == 0;
  }
  if (!text_) return;
  for (; i < size; ++i, ++offset_) byte(data[i]);
}

void DirectXNestingScan::byte(char c) {
  if (in_comment_) {
    if (c == '\n' || c == '\r') in_comment_ = false;
  } else if (in_string_) {
    if (c == '"') in_string_ = false;
  } else if (c == '"') {
    in_string_ = true;
  } else if (c == '#' || (c == '/' && last_ == '/')) {
    in_comment_ = true;
  } else if (c == '{') {
    if (depth_ <= kMaxMarkupNesting && ++depth_ > max_depth_) {
      max_depth_ = depth_;
      deepest_at_ = offset_;
    }
  } else if (c == '}' && depth_ > 0) {
    --depth_;
  }
  last_ = in_comment_ ? 0 : c;
}

namespace {

void refuse_if_too_deep(const std::string& name, const DirectXNestingScan& scan) {
  if (scan.max_depth() <= kMaxMarkupNesting) return;
  throw InputError(name, at_byte(scan.deepest_at()),
                   "DirectX .x nested deeper than " + std::to_string(kMaxMarkupNesting) +
                       " levels (the most a model file may nest)");
}

bool not_text(const DirectXNestingScan& scan) { return scan.decided() && !scan.text(); }

}  // namespace

void check_directx_nesting(const std::string& name, const char* data, std::size_t size) {
  DirectXNestingScan scan;
  scan_in_pieces(
      scan, data, size, [&](const DirectXNestingScan& s) { refuse_if_too_deep(name, s); }, not_text);
}

void check_directx_nesting_of_file(const std::string& name, const std::filesystem::path& file) {
  DirectXNestingScan scan;
  scan_file_in_pieces(
      scan, file, [&](const DirectXNestingScan& s) { refuse_if_too_deep(name, s); }, not_text);
}

}  // namespace cellbake
