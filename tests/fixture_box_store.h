// A 4 x 4 x 3 m box room (quads split 40 x 40: a far field worth sampling)
// with a 0.4 m pillar, written as DIR/box.obj and ingested serially into
// DIR/s.db: the small store the integrity, kill/resume and viewer-cache tests
// bake 1.5 m or 1 m cells of.
#pragma once

#include <filesystem>
#include <functional>
#include <sstream>

#include "pipeline/ingest.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake::test {

inline void ingest_box_with_pillar(const std::filesystem::path& dir) {
  std::ostringstream o;
  int next = 1;
  obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 40);
  obj_box(o, next, {1.8, 1.8, 0}, {2.2, 2.2, 3}, 1);
  write_text(dir / "box.obj", o.str());
  ingest_models({dir / "box.obj"}, dir / "s.db", IngestParams{},
                [](std::size_t n, const std::function<void(std::size_t)>& fn) {
                  for (std::size_t i = 0; i < n; ++i) fn(i);
                });
}

}  // namespace cellbake::test
