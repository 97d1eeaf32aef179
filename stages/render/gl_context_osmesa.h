// OSMesa backend of GlContext (built only with CELLBAKE_WITH_OSMESA).
#pragma once

#include <memory>

#include "stages/render/gl_context.h"

namespace cellbake {

// A 3.3+ core profile OSMesa context with a `width` x `height` host-memory
// default framebuffer, current on the calling thread. Throws
// std::runtime_error naming "osmesa" when it cannot be created.
std::unique_ptr<GlContext> create_osmesa_context(int width, int height);

}  // namespace cellbake
