// The replay driver: a main() for the fuzz targets of tests/fuzz without
// libFuzzer, so any compiler builds them as regression tests (ctest
// `fuzz_replay.*`; the asan job of scripts/sanitize.sh and scripts/fuzz.sh
// replay run them under ASan + UBSan).
//
//   fuzz_X [--runs N] [--seed S] [--max-len BYTES] INPUT...
//
// INPUT is a file or a folder of files (read in name order). Every input is
// run as it is, then N mutants (default 2000) are made from them with a fixed
// pseudo-random sequence (SplitMix64 from S and the target's name: the same
// mutants on every run and machine) and run one after another. A mutant is
// 1..4 stacked edits of one input, the kinds libFuzzer's MutationDispatcher
// makes: bit flips, random and "interesting" bytes and integers (0, -1,
// INT_MAX, 2^24, ...) in either byte order, truncation, deletion, insertion
// of random bytes or parser tokens ("nan", "1e400", "\n", ...), a copied
// range, a splice of two inputs; at most --max-len bytes (default 65536, as
// scripts/fuzz.sh).
//
// A finding is what libFuzzer calls one: a crash or trap (signal), an
// exception the target lets escape, one input running longer than 20 s, or
// one allocation above 2560 MiB (scripts/fuzz.sh's -rss_limit_mb; in a
// sanitizer build ASan's max_allocation_size_mb does this). The driver then
// names the input ("seed NAME" or "mutant K of NAME") on stderr, writes its
// bytes to ./fuzz-finding-TARGET (replay it with the libFuzzer build:
// `build-fuzz/tests/fuzz/TARGET fuzz-finding-TARGET`) and dies with the
// signal, so the test fails. Exit 0: every input ran.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

#if defined(__SANITIZE_ADDRESS__)
#define CELLBAKE_REPLAY_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CELLBAKE_REPLAY_ASAN 1
#endif
#endif

namespace {

constexpr unsigned kTimeoutSeconds = 20;
constexpr std::size_t kMaxAllocation = std::size_t{2560} << 20;

// ------------------------------------------------ what is running, for reports

// Set before each input; read by the signal handler (async-signal-safe: plain
// writes of preformatted bytes).
const std::uint8_t* g_data = nullptr;
std::size_t g_size = 0;
char g_label[512] = "";
char g_finding_path[512] = "";
volatile sig_atomic_t g_reported = 0;  // once per process: an abort after a report adds nothing

void write_all(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n <= 0) return;
    p += n;
    size -= std::size_t(n);
  }
}

// Names the running input on stderr and saves its bytes (signal-safe).
void report_current(const char* what) {
  if (g_reported) return;
  g_reported = 1;
  write_all(2, "\n[fuzz_replay] ", 15);
  write_all(2, what, std::strlen(what));
  write_all(2, " on ", 4);
  write_all(2, g_label, std::strlen(g_label));
  const int fd = ::open(g_finding_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    if (g_data) write_all(fd, g_data, g_size);
    ::close(fd);
    write_all(2, "; input saved as ", 17);
    write_all(2, g_finding_path, std::strlen(g_finding_path));
  }
  write_all(2, "\n", 1);
}

void on_signal(int sig) {
  report_current(sig == SIGALRM ? "timeout (one input ran over 20 s)" : strsignal(sig));
  ::signal(sig, SIG_DFL);
  ::raise(sig == SIGALRM ? SIGABRT : sig);
}

// A sanitizer's report ends the process through its own path: name the input first.
extern "C" void __sanitizer_set_death_callback(void (*)(void)) __attribute__((weak));
void on_sanitizer_death() { report_current("sanitizer report"); }

// ------------------------------------------------------- deterministic mutants

struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return n ? std::size_t(next() % n) : 0; }
};

std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

// Tokens that text parsers (OBJ, MTL, PLY, OFF, ASCII STL, TOML) treat specially.
constexpr std::string_view kTokens[] = {
    " ", "\n", "\r\n", "\t", "-", "+", ".", "/", "//", "#", "\\", "\"", "'", "[", "]", "{", "}", "=", ",",
    "0", "1", "-1", "3", "255", "65536", "2147483647", "-2147483648", "4294967295", "4294967296",
    "18446744073709551616", "1e38", "1e400", "-1e400", "nan", "inf", "-inf", "0x10", "1e-400", "true", "false",
    "v ", "vt ", "vn ", "f ", "usemtl ", "mtllib ", "newmtl ", "Kd ", "map_Kd ", "d ", "Tr ", "element ",
    "property ", "list ", "uchar ", "int ", "float ", "double ", "end_header\n", "binary_little_endian",
    "binary_big_endian", "ascii", "OFF\n", "COFF\n", "solid ", "facet normal ", "vertex ", "endloop\n",
    "[input]\n", "[cells]\n", "[sample]\n", "regions = ", "size = ", std::string_view("\0", 1)};

constexpr std::uint64_t kInterestingIntegers[] = {0, 1, 2, 3, 0x7f, 0x80, 0xff, 0x100, 0x7fff, 0x8000, 0xffff,
                                                  0x10000, 1u << 24, 1u << 26, 0x7fffffff, 0x80000000,
                                                  0xffffffff, 0x100000000ull, 0x7fffffffffffffffull,
                                                  0x8000000000000000ull, ~std::uint64_t{0}};

using Bytes = std::vector<std::uint8_t>;

void mutate_once(Bytes& b, const std::vector<Bytes>& inputs, SplitMix64& rng, std::size_t max_len) {
  switch (rng.below(11)) {
    case 0:  // flip one bit
      if (!b.empty()) b[rng.below(b.size())] ^= std::uint8_t(1u << rng.below(8));
      break;
    case 1:  // a random byte
      if (!b.empty()) b[rng.below(b.size())] = std::uint8_t(rng.next());
      break;
    case 2: {  // an interesting integer of 1, 2, 4 or 8 bytes, either byte order
      const std::size_t width = std::size_t{1} << rng.below(4);
      if (b.size() < width) break;
      std::uint64_t v = kInterestingIntegers[rng.below(std::size(kInterestingIntegers))];
      if (rng.below(4) == 0) v = std::uint64_t(b.size()) + rng.below(3) - 1;  // lengths near the input's
      if (rng.below(2)) v = ~v + 1;
      const std::size_t at = rng.below(b.size() - width + 1);
      const bool big = rng.below(2);
      for (std::size_t i = 0; i < width; ++i) b[at + (big ? width - 1 - i : i)] = std::uint8_t(v >> (8 * i));
      break;
    }
    case 3:  // add a small number to a byte
      if (!b.empty()) b[rng.below(b.size())] += std::uint8_t(int(rng.below(35)) - 17);
      break;
    case 4:  // truncate
      b.resize(rng.below(b.size() + 1));
      break;
    case 5: {  // delete a range
      if (b.empty()) break;
      const std::size_t at = rng.below(b.size()), n = 1 + rng.below(std::min<std::size_t>(b.size() - at, 64));
      b.erase(b.begin() + std::ptrdiff_t(at), b.begin() + std::ptrdiff_t(at + n));
      break;
    }
    case 6: {  // insert random bytes
      const std::size_t at = rng.below(b.size() + 1), n = 1 + rng.below(16);
      Bytes r(n);
      for (auto& c : r) c = std::uint8_t(rng.next());
      b.insert(b.begin() + std::ptrdiff_t(at), r.begin(), r.end());
      break;
    }
    case 7:
    case 8: {  // insert or overwrite with a parser token
      const std::string_view t = kTokens[rng.below(std::size(kTokens))];
      const std::size_t at = rng.below(b.size() + 1);
      if (rng.below(2) || at + t.size() > b.size())
        b.insert(b.begin() + std::ptrdiff_t(at), t.begin(), t.end());
      else
        std::copy(t.begin(), t.end(), b.begin() + std::ptrdiff_t(at));
      break;
    }
    case 9: {  // copy a range of the input to another place
      if (b.empty()) break;
      const std::size_t from = rng.below(b.size()), n = 1 + rng.below(std::min<std::size_t>(b.size() - from, 128));
      const Bytes piece(b.begin() + std::ptrdiff_t(from), b.begin() + std::ptrdiff_t(from + n));
      b.insert(b.begin() + std::ptrdiff_t(rng.below(b.size() + 1)), piece.begin(), piece.end());
      break;
    }
    default: {  // splice: a prefix of this input, a suffix of another
      const Bytes& other = inputs[rng.below(inputs.size())];
      b.resize(rng.below(b.size() + 1));
      const std::size_t from = rng.below(other.size() + 1);
      b.insert(b.end(), other.begin() + std::ptrdiff_t(from), other.end());
      break;
    }
  }
  if (b.size() > max_len) b.resize(max_len);
}

// ------------------------------------------------------------------ running

struct Input {
  std::string name;
  Bytes bytes;
};

Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void run_one(const Bytes& bytes, const std::string& label) {
  std::snprintf(g_label, sizeof g_label, "%s (%zu bytes)", label.c_str(), bytes.size());
  g_data = bytes.data();
  g_size = bytes.size();
  ::alarm(kTimeoutSeconds);
  try {
    // A copy in a buffer of its own size, so reads past the end are caught by ASan.
    std::unique_ptr<std::uint8_t[]> exact(new std::uint8_t[std::max<std::size_t>(bytes.size(), 1)]);
    if (!bytes.empty()) std::memcpy(exact.get(), bytes.data(), bytes.size());
    LLVMFuzzerTestOneInput(bytes.empty() ? nullptr : exact.get(), bytes.size());
  } catch (const std::exception& e) {
    report_current((std::string("exception escaped: ") + e.what()).c_str());
    std::abort();
  } catch (...) {
    report_current("non-standard exception escaped");
    std::abort();
  }
  ::alarm(0);
}

[[noreturn]] void usage(const char* program) {
  std::fprintf(stderr, "usage: %s [--runs N] [--seed S] [--max-len BYTES] INPUT...\n", program);
  std::exit(2);
}

}  // namespace

#ifndef CELLBAKE_REPLAY_ASAN
// libFuzzer's -malloc_limit_mb: one allocation above the limit is a finding
// (bad_alloc would otherwise be caught by the targets as a rejected input).
void* operator new(std::size_t size) {
  if (size > kMaxAllocation) {
    char what[96];
    std::snprintf(what, sizeof what, "allocation of %zu bytes (over the %zu MiB limit)", size, kMaxAllocation >> 20);
    report_current(what);
    std::abort();
  }
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const std::string target = fs::path(argv[0]).filename().string();
  std::size_t runs = 2000, max_len = 65536;
  std::uint64_t seed = 1;
  std::vector<Input> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    const auto number = [&]() -> std::uint64_t {
      if (i + 1 >= argc) usage(argv[0]);
      char* end = nullptr;
      const unsigned long long v = std::strtoull(argv[++i], &end, 10);
      if (*end != '\0') usage(argv[0]);
      return v;
    };
    if (a == "--runs") {
      runs = number();
    } else if (a == "--seed") {
      seed = number();
    } else if (a == "--max-len") {
      max_len = std::max<std::size_t>(1, number());
    } else if (a.starts_with("--")) {
      usage(argv[0]);
    } else if (fs::is_directory(argv[i])) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(argv[i]))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (const auto& f : files) inputs.push_back({f.filename().string(), read_file(f)});
    } else if (fs::is_regular_file(argv[i])) {
      inputs.push_back({fs::path(argv[i]).filename().string(), read_file(argv[i])});
    } else {
      std::fprintf(stderr, "%s: no such input '%s'\n", target.c_str(), argv[i]);
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "%s: no inputs (a seed corpus from fuzz_seeds is expected)\n", target.c_str());
    return 2;
  }
  for (auto& in : inputs)
    if (in.bytes.size() > max_len) in.bytes.resize(max_len);

  std::snprintf(g_finding_path, sizeof g_finding_path, "fuzz-finding-%s", target.c_str());
#ifdef CELLBAKE_REPLAY_ASAN
  // ASan reports SIGSEGV, SIGBUS and SIGFPE itself (then the death callback names the input).
  for (int sig : {SIGILL, SIGABRT, SIGALRM}) ::signal(sig, on_signal);
#else
  // On a stack of their own, so that a stack overflow (an importer recursing
  // without bound) is reported with its input too.
  static std::vector<char> alternate_stack(std::size_t{1} << 16);
  const stack_t alternate{alternate_stack.data(), 0, alternate_stack.size()};
  ::sigaltstack(&alternate, nullptr);
  for (int sig : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGALRM}) {
    struct sigaction action {};
    action.sa_handler = on_signal;
    action.sa_flags = SA_ONSTACK;
    ::sigaction(sig, &action, nullptr);
  }
#endif
  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(on_sanitizer_death);

  const auto start = std::chrono::steady_clock::now();
  run_one({}, "the empty input");
  for (const Input& in : inputs) run_one(in.bytes, "seed " + in.name);
  std::vector<Bytes> corpus;
  for (const Input& in : inputs) corpus.push_back(in.bytes);
  SplitMix64 rng{seed ^ fnv1a(target)};
  Bytes mutant;
  for (std::size_t k = 0; k < runs; ++k) {
    const Input& from = inputs[k % inputs.size()];
    mutant = from.bytes;
    for (std::size_t edits = 1 + rng.below(4); edits > 0; --edits) mutate_once(mutant, corpus, rng, max_len);
    run_one(mutant, "mutant " + std::to_string(k) + " of seed " + from.name + " (--seed " + std::to_string(seed) + ")");
  }
  // What runs after this (LeakSanitizer's check at exit) belongs to no one input,
  // and the last mutant's bytes are freed before it.
  g_data = nullptr;
  g_size = 0;
  std::snprintf(g_label, sizeof g_label, "the exit after all inputs (a leak from any of them)");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %zu inputs and %zu mutants ran without findings in %.1f s\n", target.c_str(), inputs.size() + 1, runs,
              seconds);
  return 0;
}
