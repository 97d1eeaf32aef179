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
  if (target && (!shown_ || shown_->id != target->id)) {
    if (!shown_) {
      shown_ = target;  // nothing to keep drawing: the draw uploads it
    } else {
      const UploadProgress part = drawer.upload_some(*target, budget);
      add(spent, part);
      if (part.complete) shown_ = target;
    }
  }
  if (heading && shown_ && target && shown_->id == target->id && heading->id != target->id &&
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
