// GL textures of a model's texture images, uploaded on first use with a full
// mip chain (trilinear filtering, the image's wrap modes) and kept in an LRU
// cache bounded in bytes, so a model with gigabytes of textures renders with
// bounded memory. One cache per GL context; the caller makes it current.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <unordered_map>

#include "stages/texture.h"

namespace cellbake {

struct GlFunctions;

using TextureLoader = std::function<std::shared_ptr<const TextureImage>(std::int64_t id)>;

class GlTextureCache {
 public:
  // `cap_bytes` bounds the GL memory of cached textures (mip chain included,
  // 4/3 of the base level); the texture being bound is kept even when it alone
  // exceeds the cap.
  GlTextureCache(const GlFunctions& gl, std::size_t cap_bytes) : gl_(gl), cap_bytes_(cap_bytes) {}
  ~GlTextureCache();  // needs the owning context current (it deletes the textures)
  GlTextureCache(const GlTextureCache&) = delete;
  GlTextureCache& operator=(const GlTextureCache&) = delete;

  // Binds texture `id` to the active texture unit, uploading it through `load`
  // when it is not cached. Throws std::runtime_error when `load` fails or
  // returns an image whose texels do not match its size.
  void bind(std::int64_t id, const TextureLoader& load);
  // Deletes every cached texture.
  void clear();
  std::size_t bytes() const { return bytes_; }
  std::size_t size() const { return entries_.size(); }
  std::uint64_t uploads() const { return uploads_; }

 private:
  struct Entry {
    unsigned name = 0;
    std::size_t bytes = 0;
    std::list<std::int64_t>::iterator recency;
  };
  void evict_beyond_cap();

  const GlFunctions& gl_;
  std::size_t cap_bytes_;
  std::size_t bytes_ = 0;
  std::uint64_t uploads_ = 0;
  std::unordered_map<std::int64_t, Entry> entries_;
  std::list<std::int64_t> lru_;  // front = most recently bound
};

}  // namespace cellbake
