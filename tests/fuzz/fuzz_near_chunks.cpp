// libFuzzer target: unpack_near_chunks (storage/cell_db.h) on arbitrary
// bytes; a list that unpacks must pack back to the same bytes' meaning.
#include <exception>

#include "storage/cell_db.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<cellbake::NearChunkRow> rows;
  try {
    rows = cellbake::unpack_near_chunks(data, size);
  } catch (const std::exception&) {
    return 0;
  }
  const auto packed = cellbake::pack_near_chunks(rows);
  const auto again = cellbake::unpack_near_chunks(packed.data(), packed.size());
  if (again.size() != rows.size()) __builtin_trap();
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (again[i].chunk_id != rows[i].chunk_id || again[i].triangles != rows[i].triangles ||
        again[i].whole != rows[i].whole)
      __builtin_trap();
  return 0;
}
