// Hitch-free cell switches for the interactive viewer: when the eye enters
// another cell, the cell drawn stays the previous one while the new cell's
// GPU uploads (far-field faces, near and far chunks) are spread over frames
// within a per-frame budget (SceneDrawer::upload_some); the switch happens on
// the frame its upload completes. What the budget leaves is spent uploading
// ahead the cell the walk is heading into (viewer/prefetch_order.h), so that
// its switch finds everything resident. No frame uploads a whole cell at once,
// except the very first cell (nothing else to draw).
#pragma once

#include <cstdint>
#include <memory>

#include "viewer/decoded_cell.h"
#include "viewer/scene_drawer.h"

namespace cellbake {

class CellSwitch {
 public:
  // The cell to draw this frame (null until a first target is given).
  // `target`: the eye's cell, decoded (null while it loads: the previous cell
  // stays). `heading`: the next cell of the walk if decoded (null: none),
  // uploaded ahead with what is left of `budget` once the target is drawn,
  // while the drawer's GPU caches are at most half full, and not on the frame
  // that switches. A target whose upload ahead completed is switched to at
  // once, without scanning it again.
  // Adds the frame's uploads to `spent`. Throws as SceneDrawer::upload_some.
  std::shared_ptr<const DecodedCell> choose(const std::shared_ptr<const DecodedCell>& target,
                                            const std::shared_ptr<const DecodedCell>& heading, SceneDrawer& drawer,
                                            const UploadBudget& budget, UploadProgress& spent);
  // The cell drawn last (null before the first).
  const std::shared_ptr<const DecodedCell>& shown() const { return shown_; }
  // Forgets the cell drawn (after a cell failed to draw).
  void reset() { shown_.reset(); }

 private:
  std::shared_ptr<const DecodedCell> shown_;
  std::int64_t heading_uploaded_ = 0;  // the heading cell whose upload ahead completed (not scanned again)
};

}  // namespace cellbake
