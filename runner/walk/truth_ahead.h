// The walk's ground truth drawn one frame ahead: a worker thread with its own
// GL context and drawer renders the truth of frame i + 1 while the caller
// draws the cells frame of frame i, so a walk keeps two cores busy. The
// truth of one camera is the same image whichever thread draws it.
#pragma once

#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "stages/chunk_source.h"
#include "stages/render/chunk_renderer.h"
#include "stages/shading.h"
#include "viewer/image_metrics.h"
#include "viewer/scene_drawer.h"

namespace cellbake {

struct TruthFrame {
  ViewFrame frame;
  SceneFrameStats stats;
};

class TruthAhead {
 public:
  // Starts the worker, which creates its context and drawer of `source`
  // (which must outlive this) lit by `lights`, drawing with `options`
  // (SceneDrawer::draw_truth). Errors (no GL context) are thrown by the first take().
  TruthAhead(const ChunkSource& source, const ShadingLights& lights, const SceneDrawOptions& options = {});
  ~TruthAhead();  // waits for a frame in progress, then stops the worker
  TruthAhead(const TruthAhead&) = delete;
  TruthAhead& operator=(const TruthAhead&) = delete;

  // Asks for the truth from `camera` at width x height; at most one request
  // is outstanding (throws std::logic_error otherwise).
  void request(const RenderCamera& camera, int width, int height);
  // Waits for the requested frame and returns it; rethrows the worker's error.
  TruthFrame take();

 private:
  void run();

  const ChunkSource& source_;
  ShadingLights lights_;
  SceneDrawOptions options_;
  std::mutex mutex_;
  std::condition_variable changed_;
  struct Request {
    RenderCamera camera;
    int width, height;
  };
  std::optional<Request> request_;
  std::optional<TruthFrame> result_;
  std::exception_ptr error_;
  bool pending_ = false, stop_ = false;
  std::thread worker_;  // last: started once everything above exists
};

}  // namespace cellbake
