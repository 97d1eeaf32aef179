#include "storage/meta_values.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "storage/cell_db.h"

namespace cellbake {
namespace {

[[noreturn]] void bad_value(const std::filesystem::path& db, const std::string& key, const std::string& value,
                            const char* what) {
  const std::string shown = value.size() > 40 ? value.substr(0, 40) + "..." : value;
  throw std::runtime_error(db.string() + ": meta '" + key + "' is '" + shown + "', not " + what +
                           " (the database is damaged or was not written by cellbake)");
}

}  // namespace

std::uint64_t parse_meta_u64(const std::filesystem::path& db, const std::string& key, const std::string& value) {
  if (value.empty() || value.size() > 20) bad_value(db, key, value, "an unsigned integer");
  for (char c : value)
    if (c < '0' || c > '9') bad_value(db, key, value, "an unsigned integer");
  errno = 0;
  const unsigned long long v = std::strtoull(value.c_str(), nullptr, 10);
  if (errno == ERANGE) bad_value(db, key, value, "an unsigned 64-bit integer");
  return v;
}

double parse_meta_double(const std::filesystem::path& db, const std::string& key, const std::string& value) {
  char* end = nullptr;
  errno = 0;
  const double v = value.empty() ? 0 : std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size() || errno == ERANGE || !std::isfinite(v))
    bad_value(db, key, value, "a finite number");
  return v;
}

std::uint64_t meta_u64(const CellDb& db, const std::string& key, std::uint64_t fallback) {
  const auto v = db.meta(key);
  return v ? parse_meta_u64(db.path(), key, *v) : fallback;
}

double meta_double(const CellDb& db, const std::string& key, double fallback) {
  const auto v = db.meta(key);
  return v ? parse_meta_double(db.path(), key, *v) : fallback;
}

}  // namespace cellbake
