// What assimp says while it reads a model: its warnings and errors ("Some
// faces had out-of-range indices. Those faces were dropped."), which it
// otherwise only writes to a logger nobody reads, so that a model that loses
// faces or materials on import says so in the ingest's warnings.
//
// Assimp's logger is process-wide: while an AssimpMessages exists, other
// threads' imports that capture wait for it (one capture at a time).
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace cellbake {

class AssimpMessages {
 public:
  // Starts capturing assimp's warnings and errors (blocks while another
  // AssimpMessages exists).
  AssimpMessages();
  // Stops capturing; assimp logs nowhere again.
  ~AssimpMessages();
  AssimpMessages(const AssimpMessages&) = delete;
  AssimpMessages& operator=(const AssimpMessages&) = delete;

  // The distinct messages so far, in order, each as " assimp warning: TEXT"
  // or " assimp error: TEXT" (ModelInfo::warnings' form); at most
  // `max_messages`, then one line counting the rest.
  std::vector<std::string> warnings(std::size_t max_messages = 8) const;

 private:
  struct Capture;
  std::unique_ptr<Capture> capture_;
};

}  // namespace cellbake
