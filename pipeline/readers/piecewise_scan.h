// Feeding a streaming scanner (markup_nesting.h, directx_nesting.h) the bytes
// of a model held in memory or read from a file, in pieces, so that a check
// before import stops at the first problem and reads a file once in constant
// memory.
#pragma once

#include <algorithm>
#include <cstddef>
#include <filesystem>

#include "pipeline/readers/buffered_input.h"

namespace cellbake {

// Feeds `data` to `scan` in 1 MiB pieces, calling `check(scan)` (which throws
// to refuse) after each, until the end or `done(scan)`.
template <class Scan, class Check, class Done>
void scan_in_pieces(Scan& scan, const char* data, std::size_t size, Check check, Done done) {
  constexpr std::size_t kPiece = std::size_t{1} << 20;
  for (std::size_t at = 0; at < size; at += kPiece) {
    scan.feed(data + at, std::min(kPiece, size - at));
    check(scan);
    if (done(scan)) return;
  }
}

// The same over `file` (plain or .gz) read with BufferedInput.
template <class Scan, class Check, class Done>
void scan_file_in_pieces(Scan& scan, const std::filesystem::path& file, Check check, Done done) {
  BufferedInput in(file);
  while (in.fetch(1)) {
    const std::size_t n = in.buffered();
    scan.feed(in.fetch(n), n);
    in.consume(n);
    check(scan);
    if (done(scan)) return;
  }
}

}  // namespace cellbake
