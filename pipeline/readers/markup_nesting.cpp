#include "pipeline/readers/markup_nesting.h"

#include "pipeline/input_error.h"
#include "pipeline/readers/piecewise_scan.h"

namespace cellbake {

void MarkupNestingScan::open_level() {
  if (depth_ > kMaxMarkupNesting) return;  // refused anyway: deepest_at() stays where the limit was passed
  if (++depth_ > max_depth_) {
    max_depth_ = depth_;
    deepest_at_ = offset_;
  }
}

void MarkupNestingScan::json_byte(char c) {
  if (in_string_) {
    if (escaped_)
      escaped_ = false;
    else if (c == '\\')
      escaped_ = true;
    else if (c == '"')
      in_string_ = false;
    return;
  }
  if (c == '"')
    in_string_ = true;
  else if (c == '{' || c == '[')
    open_level();
  else if ((c == '}' || c == ']') && depth_ > 0)
    --depth_;
}

void MarkupNestingScan::xml_byte(char c) {
  switch (xml_) {
    case Xml::text:
      if (c == '<') xml_ = Xml::open;
      break;
    case Xml::open:
      if (c == '/')
        xml_ = Xml::end_tag;
      else if (c == '?')
        xml_ = Xml::instruction;
      else if (c == '!')
        xml_ = Xml::bang, bang_count_ = 0;
      else
        xml_ = Xml::start_tag, quote_ = 0;
      break;
    case Xml::bang:  // "<!--" comment, "<![CDATA[" section, else a declaration
      ++bang_count_;
      if (bang_count_ == 1 && c == '-')
        xml_ = Xml::bang_dash;
      else if (bang_count_ == 1 && c == '[')
        xml_ = Xml::cdata;
      else
        xml_ = Xml::declaration, quote_ = 0, declaration_brackets_ = 0;
      break;
    case Xml::bang_dash:
      xml_ = c == '-' ? Xml::comment : Xml::declaration;
      last_ = before_last_ = 0;
      break;
    case Xml::comment:
      if (c == '>' && last_ == '-' && before_last_ == '-') xml_ = Xml::text;
      break;
    case Xml::cdata:
      if (c == '>' && last_ == ']' && before_last_ == ']') xml_ = Xml::text;
      break;
    case Xml::instruction:
      if (c == '>' && last_ == '?') xml_ = Xml::text;
      break;
    case Xml::declaration:
      if (quote_) {
        if (c == quote_) quote_ = 0;
      } else if (c == '"' || c == '\'') {
        quote_ = c;
      } else if (c == '[') {
        ++declaration_brackets_;
      } else if (c == ']') {
        if (declaration_brackets_ > 0) --declaration_brackets_;
      } else if (c == '>' && declaration_brackets_ == 0) {
        xml_ = Xml::text;
      }
      break;
    case Xml::start_tag:
      if (quote_) {
        if (c == quote_) quote_ = 0;
      } else if (c == '"' || c == '\'') {
        quote_ = c;
      } else if (c == '>') {
        if (last_ != '/') open_level();  // "<a/>" opens nothing
        xml_ = Xml::text;
      }
      break;
    case Xml::end_tag:
      if (c == '>') {
        if (depth_ > 0) --depth_;
        xml_ = Xml::text;
      }
      break;
  }
}

void MarkupNestingScan::feed(const char* data, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i, ++offset_) {
    const char c = data[i];
    if (!decided_) {
      const auto u = static_cast<unsigned char>(c);
      if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || u == 0xEF || u == 0xBB || u == 0xBF) continue;
      decided_ = true;
      syntax_ = c == '<'                 ? MarkupSyntax::xml
                : (c == '{' || c == '[') ? MarkupSyntax::json
                                         : MarkupSyntax::unknown;
    }
    if (syntax_ == MarkupSyntax::json) {
      json_byte(c);
    } else if (syntax_ == MarkupSyntax::xml) {
      xml_byte(c);
      before_last_ = last_;
      last_ = c;
    } else {
      return;
    }
  }
}

namespace {

void refuse_if_too_deep(const std::string& name, const MarkupNestingScan& scan) {
  if (scan.max_depth() <= kMaxMarkupNesting) return;
  throw InputError(name, at_byte(scan.deepest_at()),
                   std::string(scan.syntax() == MarkupSyntax::json ? "JSON" : "XML") +
                       " nested deeper than " + std::to_string(kMaxMarkupNesting) +
                       " levels (the most a model file may nest)");
}

bool neither_json_nor_xml(const MarkupNestingScan& scan) {
  return scan.decided() && scan.syntax() == MarkupSyntax::unknown;
}

}  // namespace

void check_markup_nesting(const std::string& name, const char* data, std::size_t size) {
  MarkupNestingScan scan;
  scan_in_pieces(
      scan, data, size, [&](const MarkupNestingScan& s) { refuse_if_too_deep(name, s); }, neither_json_nor_xml);
}

void check_markup_nesting_of_file(const std::string& name, const std::filesystem::path& file) {
  MarkupNestingScan scan;
  scan_file_in_pieces(
      scan, file, [&](const MarkupNestingScan& s) { refuse_if_too_deep(name, s); }, neither_json_nor_xml);
}

}  // namespace cellbake
