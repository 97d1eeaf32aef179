#include "pipeline/readers/contained_paths.h"

namespace cellbake {
namespace {

std::filesystem::path resolved(const std::filesystem::path& p) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(p.empty() ? "." : p, ec);
  if (ec) return {};
  std::filesystem::path canonical = std::filesystem::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal() : canonical;
}

}  // namespace

bool path_inside_folder(const std::filesystem::path& folder, const std::filesystem::path& reference) {
  const std::filesystem::path root = resolved(folder);
  const std::filesystem::path target = resolved(reference);
  if (root.empty() || target.empty()) return false;
  auto r = root.begin();
  auto t = target.begin();
  for (; r != root.end(); ++r) {
    if (r->empty()) continue;  // the trailing "" of "dir/"
    if (t == target.end() || *t != *r) return false;
    ++t;
  }
  return t != target.end() && !t->empty();  // strictly below the folder
}

}  // namespace cellbake
