// ThreadSanitizer and threads it cannot see (scripts/sanitize.sh tsan,
// docs/reliability.md). Debian's libtbb is not instrumented and its task
// pool's ITT notifications are compiled out, so TSan does not see that
// spawning a task happens before its body runs on another thread, or that a
// body finishes before the wait that joins it returns (nor that Embree's BVH
// build threads, on TBB, finish before rtcCommitScene returns): without help it
// reports every such hand-off as a race. These calls tell it exactly those
// orderings, which the libraries guarantee, where cellbake hands work over
// (runner/parallel, runner/bake_runner, stages/raycast/chunk_bvh_cache), each
// with a token of its own. No token orders two bodies that TBB may run at the
// same time, so a race between them is still reported
// (tests/sanitizers/tsan_canary.cpp checks that). Without -fsanitize=thread
// they compile to nothing.
#pragma once

#if defined(__SANITIZE_THREAD__)
#define CELLBAKE_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CELLBAKE_TSAN 1
#endif
#endif

#ifdef CELLBAKE_TSAN
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#endif

namespace cellbake::tsan {

// What the thread did so far happens before whatever follows a later
// `after(token)` on any thread.
inline void before(const void* token) {
#ifdef CELLBAKE_TSAN
  __tsan_release(const_cast<void*>(token));
#else
  (void)token;
#endif
}

inline void after(const void* token) {
#ifdef CELLBAKE_TSAN
  __tsan_acquire(const_cast<void*>(token));
#else
  (void)token;
#endif
}

}  // namespace cellbake::tsan
