// Numbers stored as text in a database's meta table, parsed strictly: a
// damaged or foreign value is an error naming the database and the key, never
// a bare "stoull"/"stod" from the standard library.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace cellbake {

class CellDb;

// The whole of `value` as a decimal unsigned integer. Throws
// std::runtime_error "DB: meta 'KEY' is 'VALUE', not a ...".
std::uint64_t parse_meta_u64(const std::filesystem::path& db, const std::string& key, const std::string& value);

// The whole of `value` as a finite number; same errors as parse_meta_u64.
double parse_meta_double(const std::filesystem::path& db, const std::string& key, const std::string& value);

// A cell database's meta `key` parsed as above, or `fallback` when absent.
std::uint64_t meta_u64(const CellDb& db, const std::string& key, std::uint64_t fallback);
double meta_double(const CellDb& db, const std::string& key, double fallback);

}  // namespace cellbake
