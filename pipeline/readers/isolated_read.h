// Reading a model in a child process (issue #37): an importer we do not
// control (assimp) parses in a fork()ed child with an address-space limit
// (setrlimit RLIMIT_AS) and a wall-time limit, and sends the triangles and the
// ModelInfo back over a pipe. A crash, stack overflow, runaway allocation or
// endless loop inside the importer then becomes an InputError naming the file
// instead of killing (or exhausting the machine under) the calling process.
//
// The child runs only the given read function and then _exit()s: no
// destructors, no atexit handlers, no other threads (fork copies only the
// caller's), so the read function must not wait on locks other threads of the
// parent may hold at the fork (ingest reads its models one at a time).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "pipeline/readers/model_reader.h"

namespace cellbake {

struct IsolationLimits {
  // Memory the child may map beyond what it inherited at the fork (its
  // address space, so reservations count too); 0 = no limit.
  std::uint64_t memory_bytes = 0;
  // Seconds the caller may wait for the child's next bytes, all waits
  // together (time spent in the caller's `emit` does not count); 0 = no limit.
  double seconds = 0;
};

// Calls `read(emit_in_child)` in a child process and `emit` here for every
// triangle it emits, in order; returns the ModelInfo `read` returned there.
// An InputError (or other exception) thrown by `read` is thrown here with the
// same message (other exceptions as std::runtime_error). Throws InputError
// naming `file` when the child dies by a signal ("FILE: IMPORTER crashed while
// reading it (signal 11, Segmentation fault)"), exceeds `limits.memory_bytes`
// ("FILE: IMPORTER needed more than N GB of memory ..."), keeps the caller
// waiting longer than `limits.seconds` ("FILE: IMPORTER took more than N s
// ...": the child is killed), or ends without an answer. An exception thrown
// by `emit` kills the child and propagates. Triangles come in batches: those
// emitted before an exception in `read` have been passed to `emit` (as with
// a reader that throws midway), those of the last batch before a crash or a
// limit may not.
ModelInfo read_in_child_process(const std::filesystem::path& file, const std::string& importer,
                                const std::function<ModelInfo(const TriangleCallback&)>& read,
                                const TriangleCallback& emit, const IsolationLimits& limits);

// The default memory limit of an isolated import: half the machine's
// physical memory (sysconf), at least 1 GiB.
std::uint64_t default_import_memory_bytes();

// "2 GB", "0.25 GB": `bytes` in GiB with at most two decimals, for messages.
std::string describe_gigabytes(std::uint64_t bytes);

}  // namespace cellbake
