#include "pipeline/readers/contained_paths.h"

#include <algorithm>
#include <cctype>
#include <vector>

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

std::filesystem::path locate_referenced_file(const std::filesystem::path& folder, std::string reference) {
  std::replace(reference.begin(), reference.end(), '\\', '/');  // Windows exporters
  const std::filesystem::path written = (folder / reference).lexically_normal();
  std::error_code ec;
  if (reference.empty() || std::filesystem::is_regular_file(written, ec)) return written;
  // The last component, after any drive letter ("C:name.png" has no slash).
  std::string name = reference.substr(reference.find_last_of('/') + 1);
  if (name.size() > 2 && name[1] == ':' && std::isalpha(static_cast<unsigned char>(name[0])))
    name.erase(0, 2);
  if (name.empty() || name == "." || name == "..") return written;
  const std::filesystem::path beside = folder / name;
  if (std::filesystem::is_regular_file(beside, ec)) return beside.lexically_normal();
  const auto lower = [](std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string wanted = lower(name);
  std::vector<std::filesystem::path> matches;
  for (std::filesystem::directory_iterator it(folder.empty() ? "." : folder, ec), end; !ec && it != end;
       it.increment(ec))
    if (lower(it->path().filename().string()) == wanted && it->is_regular_file(ec))
      matches.push_back(folder / it->path().filename());
  if (matches.empty()) return written;
  return std::min_element(matches.begin(), matches.end())->lexically_normal();
}

}  // namespace cellbake
