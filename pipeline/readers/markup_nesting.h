// Nesting depth of JSON and XML model files, measured before any importer
// parses them: the importers assimp uses for glTF (rapidjson), COLLADA, X3D
// and other XML formats recurse once per nesting level, so a file nested
// 100,000 deep overflows the stack inside the import. A streaming count over
// the bytes (JSON brackets outside strings; XML start and end tags outside
// comments, CDATA, processing instructions and quoted attribute values) finds
// such files in one pass with constant memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace cellbake {

// Deeper JSON or XML nesting is refused before import (documented in docs/reliability.md).
inline constexpr int kMaxMarkupNesting = 2048;

enum class MarkupSyntax { unknown, json, xml };

// Counts nesting over bytes fed in order, in pieces of any size. The syntax is
// taken from the first byte that is not blank or a UTF-8 byte order mark:
// '{' or '[' is JSON, '<' is XML, anything else is neither (nothing counted).
class MarkupNestingScan {
 public:
  void feed(const char* data, std::size_t size);
  MarkupSyntax syntax() const { return syntax_; }
  // True once the first significant byte has been seen (syntax() is final).
  bool decided() const { return decided_; }
  // The deepest level, counted up to kMaxMarkupNesting + 1 (beyond, the scan
  // only tells that the limit was passed).
  int max_depth() const { return max_depth_; }
  // Byte offset at which max_depth() was first reached.
  std::uint64_t deepest_at() const { return deepest_at_; }

 private:
  void json_byte(char c);
  void xml_byte(char c);
  void open_level();

  MarkupSyntax syntax_ = MarkupSyntax::unknown;
  bool decided_ = false;
  std::uint64_t offset_ = 0;
  int depth_ = 0, max_depth_ = 0;
  std::uint64_t deepest_at_ = 0;
  // JSON state
  bool in_string_ = false, escaped_ = false;
  // XML state
  enum class Xml {
    text,
    open,
    bang,
    bang_dash,
    start_tag,
    end_tag,
    comment,
    cdata,
    instruction,
    declaration
  };
  Xml xml_ = Xml::text;
  char quote_ = 0;                   // inside a quoted attribute value (start tag) or declaration
  char last_ = 0, before_last_ = 0;  // the previous two bytes (comment, CDATA, PI and "/>" ends)
  int bang_count_ = 0;               // bytes seen after "<!"
  int declaration_brackets_ = 0;     // DOCTYPE internal subset
};

// Throws InputError naming `name` when the bytes nest deeper than
// kMaxMarkupNesting: "JSON nested N levels deep (byte B), more than the 2048
// levels a model file may nest". Data that is neither JSON nor XML passes.
void check_markup_nesting(const std::string& name, const char* data, std::size_t size);

// The same over a model file read in pieces (plain or .gz, BufferedInput);
// reads it once, stops at the first level too deep or at the end.
void check_markup_nesting_of_file(const std::string& name, const std::filesystem::path& file);

}  // namespace cellbake
