#include "stages/render/gl_texture_cache.h"

#include <stdexcept>
#include <string>

#include "stages/render/gl_functions.h"

namespace cellbake {
namespace {

GLint gl_wrap(TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::clamp:
      return GL_CLAMP_TO_EDGE;
    case TextureWrap::mirror:
      return GL_MIRRORED_REPEAT;
    default:
      return GL_REPEAT;
  }
}

}  // namespace

GlTextureCache::~GlTextureCache() {
  try {
    clear();
  } catch (...) {
    // The context's objects go with it.
  }
}

void GlTextureCache::clear() {
  for (auto& [id, entry] : entries_) gl_.DeleteTextures(1, &entry.name);
  entries_.clear();
  lru_.clear();
  bytes_ = 0;
}

void GlTextureCache::evict_beyond_cap() {
  while (bytes_ > cap_bytes_ && lru_.size() > 1) {
    auto victim = entries_.find(lru_.back());
    lru_.pop_back();
    gl_.DeleteTextures(1, &victim->second.name);
    bytes_ -= victim->second.bytes;
    entries_.erase(victim);
  }
}

void GlTextureCache::bind(std::int64_t id, const TextureLoader& load) {
  if (auto it = entries_.find(id); it != entries_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.recency);
    gl_.BindTexture(GL_TEXTURE_2D, it->second.name);
    return;
  }
  const std::shared_ptr<const TextureImage> image = load ? load(id) : nullptr;
  const std::string where = "texture " + std::to_string(id);
  if (!image) throw std::runtime_error(where + ": no texture loader returned it");
  if (image->width <= 0 || image->height <= 0 ||
      image->texels.size() != std::size_t(image->width) * std::size_t(image->height))
    throw std::runtime_error(where + ": texels do not match its size");
  Entry entry;
  gl_.GenTextures(1, &entry.name);
  gl_.BindTexture(GL_TEXTURE_2D, entry.name);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  // Texels are bottom row first, which is GL's t = 0 row: no flip.
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image->width, image->height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 image->texels.data());
  gl_.GenerateMipmap(GL_TEXTURE_2D);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, gl_wrap(image->wrap_u));
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, gl_wrap(image->wrap_v));
  check_gl_error(gl_, ("gl_texture_cache: " + where).c_str());
  entry.bytes = image->bytes() * 4 / 3;
  lru_.push_front(id);
  entry.recency = lru_.begin();
  bytes_ += entry.bytes;
  ++uploads_;
  entries_[id] = entry;
  evict_beyond_cap();
}

}  // namespace cellbake
