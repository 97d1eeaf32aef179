#include "pipeline/readers/isolated_read.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "pipeline/input_error.h"

namespace cellbake {
namespace {

// The child's exit codes besides 0 (answered): its read threw (the message
// was sent), or it ran out of memory under the limit.
constexpr int kThrewExit = 3;
constexpr int kMemoryExit = 4;
constexpr int kPipeExit = 5;

// Record tags on the pipe: 'T' triangles, 'I' the ModelInfo (the last record
// of a read that succeeded), 'E' an InputError's message, 'X' another
// exception's message. Each record: tag byte, u64 payload length, payload.
constexpr std::size_t kTriangleBytes = 9 * 8 + 12 + 6 * 4 + 9 * 4 + 1 + 4;
constexpr std::size_t kTrianglesPerRecord = 4096;

// Appends plain values to a byte string in this machine's layout (both ends
// are the same program).
struct Writer {
  std::string bytes;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void str(const std::string& s) {
    put(std::uint64_t(s.size()));
    bytes += s;
  }
};

// Reads what Writer wrote; throws std::runtime_error past the end.
struct Reader {
  const char* p;
  const char* end;
  template <class T>
  T get() {
    T v;
    need(sizeof v);
    std::memcpy(&v, p, sizeof v);
    p += sizeof v;
    return v;
  }
  std::string str() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s(p, n);
    p += n;
    return s;
  }
  void need(std::uint64_t n) const {
    if (n > std::uint64_t(end - p)) throw std::runtime_error("truncated record from the import process");
  }
};

void put_triangle(Writer& w, const Triangle& t) {
  for (const Vec3d& p : t.p) w.put(p.x), w.put(p.y), w.put(p.z);
  for (const Rgba8& c : t.color) w.put(c.r), w.put(c.g), w.put(c.b), w.put(c.a);
  for (const Uv& uv : t.uv) w.put(uv.u), w.put(uv.v);
  for (const Vec3f& n : t.normal) w.put(n.x), w.put(n.y), w.put(n.z);
  w.put(std::uint8_t(t.has_normals));
  w.put(t.material);
}

Triangle get_triangle(Reader& r) {
  Triangle t;
  for (Vec3d& p : t.p) p.x = r.get<double>(), p.y = r.get<double>(), p.z = r.get<double>();
  for (Rgba8& c : t.color)
    c.r = r.get<std::uint8_t>(), c.g = r.get<std::uint8_t>(), c.b = r.get<std::uint8_t>(),
    c.a = r.get<std::uint8_t>();
  for (Uv& uv : t.uv) uv.u = r.get<float>(), uv.v = r.get<float>();
  for (Vec3f& n : t.normal) n.x = r.get<float>(), n.y = r.get<float>(), n.z = r.get<float>();
  t.has_normals = r.get<std::uint8_t>() != 0;
  t.material = r.get<std::uint32_t>();
  return t;
}

void put_rgba(Writer& w, const Rgba8& c) { w.put(c.r), w.put(c.g), w.put(c.b), w.put(c.a); }
Rgba8 get_rgba(Reader& r) {
  Rgba8 c;
  c.r = r.get<std::uint8_t>(), c.g = r.get<std::uint8_t>(), c.b = r.get<std::uint8_t>(), c.a = r.get<std::uint8_t>();
  return c;
}

std::string encode_info(const ModelInfo& info) {
  Writer w;
  w.put(std::uint64_t(info.materials.size()));
  for (const Material& m : info.materials) {
    w.str(m.name);
    put_rgba(w, m.color);
    w.str(m.texture);
    w.put(m.texture_id);
    w.put(std::uint8_t(m.alpha_test));
  }
  w.put(std::uint64_t(info.textures.size()));
  for (const auto& [material, t] : info.textures) {
    w.put(material);
    w.str(t.file.string());
    w.str(std::string(t.encoded.begin(), t.encoded.end()));
    w.str(t.format_hint);
    w.put(std::uint64_t(t.texels.size()));
    for (const Rgba8& c : t.texels) put_rgba(w, c);
    w.put(t.width), w.put(t.height);
    w.put(t.wrap_u), w.put(t.wrap_v);
    w.put(std::uint8_t(t.alpha_allowed));
  }
  w.put(info.vertex_colours);
  put_rgba(w, info.uniform_vertex_colour);
  w.put(info.triangles_emitted);
  w.put(info.polygons_triangulated);
  w.str(info.format);
  w.str(info.up);
  w.str(info.up_source);
  w.put(std::uint64_t(info.warnings.size()));
  for (const std::string& s : info.warnings) w.str(s);
  return std::move(w.bytes);
}

ModelInfo decode_info(Reader r) {
  ModelInfo info;
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) {
    Material m;
    m.name = r.str();
    m.color = get_rgba(r);
    m.texture = r.str();
    m.texture_id = r.get<std::int64_t>();
    m.alpha_test = r.get<std::uint8_t>() != 0;
    info.materials.push_back(std::move(m));
  }
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) {
    const auto material = r.get<std::uint32_t>();
    TextureInput t;
    t.file = r.str();
    const std::string encoded = r.str();
    t.encoded.assign(encoded.begin(), encoded.end());
    t.format_hint = r.str();
    const auto texels = r.get<std::uint64_t>();
    r.need(texels * 4);
    t.texels.reserve(texels);
    for (std::uint64_t i = 0; i < texels; ++i) t.texels.push_back(get_rgba(r));
    t.width = r.get<int>(), t.height = r.get<int>();
    t.wrap_u = r.get<TextureWrap>(), t.wrap_v = r.get<TextureWrap>();
    t.alpha_allowed = r.get<std::uint8_t>() != 0;
    info.textures[material] = std::move(t);
  }
  info.vertex_colours = r.get<VertexColourUse>();
  info.uniform_vertex_colour = get_rgba(r);
  info.triangles_emitted = r.get<std::uint64_t>();
  info.polygons_triangulated = r.get<std::uint64_t>();
  info.format = r.str();
  info.up = r.str();
  info.up_source = r.str();
  for (auto n = r.get<std::uint64_t>(); n > 0; --n) info.warnings.push_back(r.str());
  return info;
}

// The child's side of the pipe: whole records, written in full or _exit.
class RecordPipe {
 public:
  explicit RecordPipe(int fd) : fd_(fd) {}
  void triangle(const Triangle& t) {
    put_triangle(triangles_, t);
    if (++pending_ == kTrianglesPerRecord) flush();
  }
  void flush() {
    if (pending_ == 0) return;
    record('T', triangles_.bytes);
    triangles_.bytes.clear();
    pending_ = 0;
  }
  void record(char tag, const std::string& payload) {
    const std::uint64_t n = payload.size();
    char head[9];
    head[0] = tag;
    std::memcpy(head + 1, &n, 8);
    write_all(head, 9);
    write_all(payload.data(), payload.size());
  }

 private:
  void write_all(const char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t w = ::write(fd_, p, n);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) ::_exit(kPipeExit);
      p += w;
      n -= std::size_t(w);
    }
  }
  int fd_;
  Writer triangles_;
  std::size_t pending_ = 0;
};

// The address space this process has mapped now (/proc/self/statm), bytes; 0 when unknown.
std::uint64_t mapped_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  return pages * std::uint64_t(::sysconf(_SC_PAGESIZE));
}

[[noreturn]] void run_child(int fd, const std::function<ModelInfo(const TriangleCallback&)>& read,
                            const IsolationLimits& limits) {
  // Only the pipe stays open beyond stdin/out/err: a sibling child of another
  // thread must not hold our pipe's write end, nor we theirs.
  if (fd > 3) ::close_range(3, unsigned(fd) - 1, 0);
  ::close_range(unsigned(fd) + 1, ~0U, 0);
  ::signal(SIGPIPE, SIG_DFL);
  const rlimit no_core{0, 0};  // a crashed import leaves no core file of the whole process
  ::setrlimit(RLIMIT_CORE, &no_core);
  if (limits.memory_bytes > 0) {
    const rlim_t cap = rlim_t(mapped_bytes() + limits.memory_bytes);
    const rlimit limit{cap, cap};
    ::setrlimit(RLIMIT_AS, &limit);
  }
  std::set_new_handler([] { ::_exit(kMemoryExit); });
  RecordPipe out(fd);
  try {
    const ModelInfo info = read([&](const Triangle& t) { out.triangle(t); });
    out.flush();
    out.record('I', encode_info(info));
    ::_exit(0);
  } catch (const std::bad_alloc&) {
    ::_exit(kMemoryExit);
  } catch (const InputError& e) {
    out.flush();
    out.record('E', e.what());
  } catch (const std::exception& e) {
    out.flush();
    out.record('X', e.what());
  } catch (...) {
    out.flush();
    out.record('X', "unknown exception");
  }
  ::_exit(kThrewExit);
}

// The child process until it has been waited for: killed and reaped when
// the caller leaves early (its emit threw, a limit was reached).
class Child {
 public:
  Child(pid_t pid, int fd) : pid_(pid), fd_(fd) {}
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      wait();
    }
    ::close(fd_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  int fd() const { return fd_; }
  // Kills the child (a limit was reached) and reaps it.
  void kill() {
    ::kill(pid_, SIGKILL);
    wait();
  }
  // Reaps the child; its wait status.
  int wait() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return status;
  }

 private:
  pid_t pid_;
  int fd_;
};

std::string seconds_text(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", s);
  return text;
}

}  // namespace

std::uint64_t default_import_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  const std::uint64_t half = pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page) / 2 : 0;
  return std::max(half, std::uint64_t{1} << 30);
}

std::string describe_gigabytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", double(bytes) / double(std::uint64_t{1} << 30));
  std::string s = text;
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s + " GB";
}

ModelInfo read_in_child_process(const std::filesystem::path& file, const std::string& importer,
                                const std::function<ModelInfo(const TriangleCallback&)>& read,
                                const TriangleCallback& emit, const IsolationLimits& limits) {
  const std::string name = file.string();
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw std::runtime_error(name + ": cannot create a pipe for the import process: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(name + ": cannot start the import process: " + std::strerror(error));
  }
  if (pid == 0) {
    ::close(fds[0]);
    run_child(fds[1], read, limits);
  }
  ::close(fds[1]);
  Child child(pid, fds[0]);

  std::string pending;  // bytes read, not yet a whole record
  std::size_t at = 0;   // the first unparsed byte of `pending`
  bool answered = false;
  ModelInfo info;
  std::string error, error_kind;
  double waited = 0;
  std::vector<char> buffer(std::size_t(1) << 20);
  for (;;) {
    pollfd p{child.fd(), POLLIN, 0};
    const auto start = std::chrono::steady_clock::now();
    int timeout_ms = -1;
    if (limits.seconds > 0) timeout_ms = int(std::ceil(std::max(0.0, limits.seconds - waited) * 1000));
    const int ready = ::poll(&p, 1, timeout_ms);
    waited += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {  // only with a time limit: the waits have used it up
      child.kill();
      throw InputError(name, "",
                       importer + " took more than " + seconds_text(limits.seconds) +
                           " s to read it and was stopped (the import time limit)");
    }
    const ssize_t n = ::read(child.fd(), buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // end of file: the child is done (or gone)
    pending.append(buffer.data(), std::size_t(n));
    while (pending.size() - at >= 9) {
      std::uint64_t length;
      std::memcpy(&length, pending.data() + at + 1, 8);
      if (pending.size() - at - 9 < length) break;
      const char tag = pending[at];
      Reader r{pending.data() + at + 9, pending.data() + at + 9 + length};
      if (tag == 'T') {
        while (r.p < r.end) emit(get_triangle(r));
      } else if (tag == 'I') {
        info = decode_info(r);
        answered = true;
      } else {
        error.assign(r.p, r.end);
        error_kind = tag;
      }
      at += 9 + length;
    }
    if (at > (std::size_t(1) << 20)) pending.erase(0, std::exchange(at, 0));
  }
  const int status = child.wait();
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    const std::string what = std::to_string(signal) + ", " + ::strsignal(signal);
    if (signal == SIGKILL)
      throw InputError(name, "", importer + " was killed while reading it (signal " + what +
                                     "; the system may have run out of memory)");
    throw InputError(name, "", importer + " crashed while reading it (signal " + what + ")");
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == kMemoryExit)
    throw InputError(name, "",
                     importer + " needed more than " + describe_gigabytes(limits.memory_bytes) +
                         " of memory to read it and was stopped (the import memory limit)");
  if (code == 0 && answered) return info;
  if (code == kThrewExit && error_kind == "E") throw InputError(InputError::Formed{}, error);
  if (code == kThrewExit && error_kind == "X") throw std::runtime_error(error);
  throw InputError(name, "",
                   "the process reading it with " + importer + " ended without an answer (exit status " +
                       std::to_string(code) + ")");
}

}  // namespace cellbake
