#include "viewer/cell_switch.h"

namespace cellbake {
namespace {

void add(UploadProgress& total, const UploadProgress& part) {
  total.bytes += part.bytes;
  total.items += part.items;
  total.milliseconds += part.milliseconds;
}

}  // namespace

std::shared_ptr<const DecodedCell> CellSwitch::choose(const std::shared_ptr<const DecodedCell>& target,
                                                      const std::shared_ptr<const DecodedCell>& heading,
                                                      SceneDrawer& drawer, const UploadBudget& budget,
                                                      UploadProgress& spent) {
  bool switched = false;
  if (target && (!shown_ || shown_->id != target->id)) {
    if (!shown_ || target->id == heading_uploaded_) {
      // Nothing to keep drawing (the draw uploads it), or uploaded ahead already.
      shown_ = target;
      switched = true;
    } else {
      const UploadProgress part = drawer.upload_some(*target, budget);
      add(spent, part);
      if (part.complete) shown_ = target, switched = true;
    }
  }
  // The frame that switches draws a new cell: it starts no upload ahead.
  if (!switched && heading && shown_ && target && shown_->id == target->id && heading->id != target->id &&
      heading->id != heading_uploaded_ && spent.bytes < budget.bytes && spent.milliseconds < budget.milliseconds &&
      drawer.gpu_caches_below(0.5)) {
    const UploadBudget rest{budget.bytes - spent.bytes, budget.milliseconds - spent.milliseconds};
    const UploadProgress part = drawer.upload_some(*heading, rest);
    add(spent, part);
    if (part.complete) heading_uploaded_ = heading->id;
  }
  return shown_;
}

}  // namespace cellbake
