#include "pipeline/scenes/scene_ply_writer.h"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

#include "storage/output_file.h"

namespace cellbake {
namespace {

constexpr std::size_t kBufferBytes = 1 << 22;
constexpr int kCountWidth = 20;  // digits of 2^64 - 1

// Counts padded with trailing spaces, so the header length never depends on them.
std::string ply_header(std::uint64_t vertices, std::uint64_t faces, const SceneParams& params) {
  auto padded = [](std::uint64_t n) {
    std::string s = std::to_string(n);
    s.resize(kCountWidth, ' ');
    return s;
  };
  static constexpr const char* kKinds[] = {"plant", "house", "city"};
  return "ply\n"
         "format binary_little_endian 1.0\n"
         "comment cellbake generate: kind " +
         std::string(kKinds[static_cast<int>(params.kind)]) + " seed " + std::to_string(params.seed) +
         " target_triangles " + std::to_string(params.target_triangles) + "\n" + "element vertex " +
         padded(vertices) + "\n" +
         "property float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
         "element face " +
         padded(faces) + "\n" +
         "property list uchar uint vertex_indices\n"
         "end_header\n";
}

// A binary output file with a large write buffer; every failure names the file.
class BinaryFile {
 public:
  BinaryFile(const std::filesystem::path& path, const char* mode) : path_(path) {
    file_ = std::fopen(path.c_str(), mode);
    if (!file_) throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
    buffer_.reserve(kBufferBytes);
  }
  ~BinaryFile() {
    if (file_) std::fclose(file_);
  }
  BinaryFile(const BinaryFile&) = delete;
  BinaryFile& operator=(const BinaryFile&) = delete;

  // Room for `bytes` more bytes at the end of the buffer (flushing first if needed).
  unsigned char* grow(std::size_t bytes) {
    if (buffer_.size() + bytes > kBufferBytes) flush();
    const std::size_t at = buffer_.size();
    buffer_.resize(at + bytes);
    return buffer_.data() + at;
  }
  void write(const void* data, std::size_t bytes) {
    flush();
    if (bytes && std::fwrite(data, 1, bytes, file_) != bytes) fail("cannot write");
  }
  void flush() {
    if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      fail("cannot write");
    buffer_.clear();
  }
  void seek(long offset) {
    flush();
    if (std::fseek(file_, offset, SEEK_SET) != 0) fail("cannot seek");
  }
  FILE* handle() { return file_; }
  void close() {
    flush();
    FILE* f = file_;
    file_ = nullptr;
    if (std::fclose(f) != 0) fail("cannot close");
  }
  [[noreturn]] void fail(const char* what) const {
    throw std::runtime_error(path_.string() + ": " + what + ": " + std::strerror(errno));
  }

 private:
  std::filesystem::path path_;
  FILE* file_ = nullptr;
  std::vector<unsigned char> buffer_;
};

template <typename T>
void store_le(unsigned char* at, T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(at, &value, sizeof(T));
  } else {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T); ++i) at[i] = bytes[sizeof(T) - 1 - i];
  }
}

// Removes the scratch files unless told the output was committed.
struct ScratchFiles {
  std::vector<std::filesystem::path> paths;
  ~ScratchFiles() {
    std::error_code ec;
    for (const auto& p : paths) std::filesystem::remove(p, ec);
  }
};

}  // namespace

SceneSummary generate_scene_to_ply(const SceneParams& params, const std::filesystem::path& out) {
  check_output_target(out, {});  // never over a database, a device or a link
  std::filesystem::path tmp = out;
  tmp += ".tmp";
  std::filesystem::path faces_path = out;
  faces_path += ".faces.tmp";
  ScratchFiles scratch{{tmp, faces_path}};

  BinaryFile ply(tmp, "wb");
  BinaryFile faces(faces_path, "w+b");
  const std::string blank_header = ply_header(0, 0, params);
  ply.write(blank_header.data(), blank_header.size());

  std::uint64_t vertex_base = 0, face_count = 0;
  const SceneSummary summary = generate_scene(params, [&](const TriangleMesh& part) {
    if (vertex_base + part.positions.size() > 0xFFFFFFFFull)
      throw std::runtime_error(out.string() + ": more than 2^32 vertices do not fit PLY uint indices");
    for (std::size_t i = 0; i < part.positions.size(); ++i) {
      unsigned char* v = ply.grow(16);
      const Vec3d& p = part.positions[i];
      store_le(v, static_cast<float>(p.x));
      store_le(v + 4, static_cast<float>(p.y));
      store_le(v + 8, static_cast<float>(p.z));
      const Rgba8 c = part.colors[i];
      v[12] = c.r;
      v[13] = c.g;
      v[14] = c.b;
      v[15] = c.a;
    }
    const auto base = static_cast<std::uint32_t>(vertex_base);
    for (std::size_t t = 0; t + 2 < part.indices.size(); t += 3) {
      unsigned char* f = faces.grow(13);
      f[0] = 3;
      store_le(f + 1, base + part.indices[t]);
      store_le(f + 5, base + part.indices[t + 1]);
      store_le(f + 9, base + part.indices[t + 2]);
    }
    vertex_base += part.positions.size();
    face_count += part.triangle_count();
  });

  // Append the faces, then fill in the real counts.
  faces.seek(0);
  std::vector<unsigned char> chunk(kBufferBytes);
  for (;;) {
    const std::size_t n = std::fread(chunk.data(), 1, chunk.size(), faces.handle());
    if (n > 0) ply.write(chunk.data(), n);
    if (n < chunk.size()) {
      if (std::ferror(faces.handle())) faces.fail("cannot read back");
      break;
    }
  }
  faces.close();
  const std::string header = ply_header(vertex_base, face_count, params);
  if (header.size() != blank_header.size()) throw std::logic_error("scene ply writer: header length changed");
  ply.seek(0);
  ply.write(header.data(), header.size());
  ply.close();

  check_output_target(out, {});  // nothing was put there meanwhile that must stay
  std::error_code ec;
  std::filesystem::rename(tmp, out, ec);
  if (ec)
    throw std::runtime_error(out.string() + ": cannot rename " + tmp.string() + " onto it: " + ec.message());
  return summary;
}

}  // namespace cellbake
