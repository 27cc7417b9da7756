// JSON on nlohmann-json3 (json.h). Reading runs nlohmann's SAX parser over an
// iterator that counts what the lexer consumes: when the parser reports a
// value, the last non-blank byte read is that value's last byte ('{' or '['
// for containers, the closing quote of a string, a number's last digit or
// the byte right after it, which is on the same line), so its line is the
// value's line (no JSON token spans lines). JsonTreeBuilder turns the events
// into JsonValues and adds what nlohmann does not check (duplicate keys,
// depth); parse errors become "source:line:column: message". Writing
// keeps tactforce's layout and number format (nlohmann would print 1e6 as
// 1000000.0) and uses nlohmann's string escaping.
#include "tactforce/io/json.h"
#include "tactforce/io/status_macros.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <optional>

#include <nlohmann/json.hpp>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/match.h"
#include "absl/strings/string_view.h"
#include "absl/strings/strip.h"
#include "tactforce/io/text_file.h"

namespace tactforce::io {
namespace {

using Json = nlohmann::json;

// What the lexer has consumed so far.
struct ReadProgress {
  const char* begin = nullptr;
  size_t last_significant = 0;  // offset of the last non-blank byte read
  int last_significant_line = 1;
  size_t last_significant_line_start = 0;  // offset of the first byte of that line
  int line = 1;                            // line of the next byte
  size_t line_start = 0;                   // offset of the first byte of `line`
};

// A byte iterator over the text that records each byte the lexer reads.
class CountingIterator {
 public:
  using iterator_category = std::input_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  CountingIterator(const char* at, ReadProgress* progress) : at_(at), progress_(progress) {}
  reference operator*() const { return *at_; }
  CountingIterator& operator++() {
    const char c = *at_;
    const size_t offset = static_cast<size_t>(at_ - progress_->begin);
    if (c == '\n') {
      ++progress_->line;
      progress_->line_start = offset + 1;
    } else if (c != ' ' && c != '\t' && c != '\r') {
      progress_->last_significant = offset;
      progress_->last_significant_line = progress_->line;
      progress_->last_significant_line_start = progress_->line_start;
    }
    ++at_;
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator before = *this;
    ++*this;
    return before;
  }
  bool operator==(const CountingIterator& other) const { return at_ == other.at_; }
  bool operator!=(const CountingIterator& other) const { return at_ != other.at_; }

 private:
  const char* at_;
  ReadProgress* progress_;
};

// At most 40 bytes of a token for a message.
std::string Shortened(absl::string_view token) {
  if (token.size() <= 40) return std::string(token);
  return absl::StrCat(token.substr(0, 37), "...");
}

// nlohmann's reason without its prefixes, as "expected X, found Y 'token'"
// or "<lexer error> (read 'token')". `what` is e.what(), e.g.
// "[json.exception.parse_error.101] parse error at line 1, column 9: syntax
// error while parsing object separator - unexpected number literal; expected ':'".
std::string Reason(absl::string_view what, absl::string_view token) {
  if (const size_t p = what.find("] "); p != absl::string_view::npos) what.remove_prefix(p + 2);
  if (absl::ConsumePrefix(&what, "parse error")) {
    if (const size_t p = what.find(": "); p != absl::string_view::npos) what.remove_prefix(p + 2);
  }
  if (!absl::ConsumePrefix(&what, "syntax error")) return std::string(what);
  if (const size_t p = what.find(" - "); p != absl::string_view::npos) what.remove_prefix(p + 3);
  absl::string_view expected, last_read;
  if (const size_t p = what.find("; expected "); p != absl::string_view::npos) {
    expected = what.substr(p + 2);
    what = what.substr(0, p);
  }
  if (const size_t p = what.find("; last read: "); p != absl::string_view::npos) {
    last_read = what.substr(p + 13);
    what = what.substr(0, p);
  }
  std::string found(what);
  if (absl::ConsumePrefix(&what, "unexpected ")) {
    found = std::string(what);
    // Literals show their text; punctuation and "end of input" name themselves.
    if (absl::EndsWith(what, "literal") && !token.empty())
      absl::StrAppend(&found, token.front() == '"' ? " " : " '", Shortened(token),
                      token.front() == '"' ? "" : "'");
  } else if (!last_read.empty()) {
    absl::StrAppend(&found, " (read ", Shortened(last_read), ")");
  }
  if (expected.empty()) return found;
  return absl::StrCat(expected, ", found ", found);
}

}  // namespace

// Builds the JsonValue tree from nlohmann's SAX events (see the file comment).
class JsonTreeBuilder {
 public:
  JsonTreeBuilder(std::string_view text, const std::string& source, const ReadProgress* progress)
      : text_(text), source_(source), progress_(progress) {}

  bool null() { return Add(JsonValue()); }
  bool boolean(bool v) { return Add(JsonValue::Bool(v)); }
  bool number_integer(std::int64_t v) { return Add(JsonValue::Number(static_cast<double>(v))); }
  bool number_unsigned(std::uint64_t v) { return Add(JsonValue::Number(static_cast<double>(v))); }
  bool number_float(double v, const std::string& /*text*/) { return Add(JsonValue::Number(v)); }
  bool string(std::string& v) { return Add(JsonValue::String(std::move(v))); }
  bool binary(Json::binary_t& /*bytes*/) {
    return Fail("binary values are not JSON", progress_->last_significant);
  }
  bool start_object(std::size_t /*size*/) { return Open(JsonValue::Type::kObject); }
  bool start_array(std::size_t /*size*/) { return Open(JsonValue::Type::kArray); }
  bool end_object() { return Close(); }
  bool end_array() { return Close(); }
  bool key(std::string& k) {
    Container& object = open_.back();
    if (!object.keys.insert(k).second)
      return Fail(absl::StrCat("duplicate key '", Shortened(k), "'"),
                  KeyStart(progress_->last_significant));
    object.key = std::move(k);
    // The key token ends at the last byte read, on the current line.
    object.key_line = progress_->last_significant_line;
    object.key_column = Column(KeyStart(progress_->last_significant));
    return true;
  }
  bool parse_error(std::size_t position, const std::string& last_token, const Json::exception& e) {
    // `position` counts the bytes read, the offending one last.
    return Fail(Reason(e.what(), last_token), position > 0 ? position - 1 : 0);
  }

  absl::StatusOr<JsonValue> Finish(bool parsed) {
    TF_RETURN_IF_ERROR(error_);
    if (!parsed || !root_) return Error("no JSON value", text_.size());
    return *std::move(root_);
  }

 private:
  struct Container {
    JsonValue value;
    std::string key;                        // objects: the key of the next member
    int key_line = 0, key_column = 0;       // objects: where that key starts
    absl::flat_hash_set<std::string> keys;  // objects: keys so far
  };

  // 1-based byte column of `offset`, which is on the last significant line.
  int Column(size_t offset) const {
    return static_cast<int>(offset - progress_->last_significant_line_start) + 1;
  }
  JsonValue At(JsonValue value) const {
    value.line_ = progress_->last_significant_line;
    value.column_ = Column(progress_->last_significant);
    return value;
  }
  // A scalar, at its first byte (the lexer has read to its last byte or
  // the one after; a token never spans lines).
  bool Add(JsonValue value) {
    const bool quoted = value.is_string();
    value = At(std::move(value));
    value.column_ = Column(ScalarStart(progress_->last_significant, quoted));
    return Place(std::move(value));
  }
  // Into the open container, or as the document.
  bool Place(JsonValue value) {
    if (open_.empty()) {
      root_ = std::move(value);
    } else if (Container& parent = open_.back(); parent.value.is_array()) {
      parent.value.array_.push_back(std::move(value));
    } else {
      parent.value.members_.emplace_back(std::move(parent.key), std::move(value));
      parent.value.key_positions_.push_back({parent.key_line, parent.key_column});
    }
    return true;
  }
  bool Open(JsonValue::Type type) {
    if (static_cast<int>(open_.size()) >= kMaxJsonDepth)
      return Fail(absl::StrCat("nesting deeper than ", kMaxJsonDepth, " levels"),
                  progress_->last_significant);
    Container c;
    c.value.type_ = type;
    c.value = At(std::move(c.value));
    open_.push_back(std::move(c));
    return true;
  }
  // The innermost container is complete (it keeps the line of its '{' or '[').
  bool Close() {
    JsonValue value = std::move(open_.back().value);
    open_.pop_back();
    return Place(std::move(value));
  }
  // Offset of the opening quote of the string whose closing quote is at `end`.
  // First byte of the unquoted scalar (number, true, false, null) that ends
  // at `end` or right before it.
  size_t ScalarStart(size_t end, bool quoted) const {
    if (quoted) return KeyStart(end);
    auto in_token = [](char c) {
      return absl::ascii_isalnum(c) || c == '+' || c == '-' || c == '.';
    };
    size_t i = std::min(end, text_.size() - 1);
    if (i > 0 && !in_token(text_[i])) --i;
    while (i > 0 && in_token(text_[i - 1])) --i;
    return i;
  }
  size_t KeyStart(size_t end) const {
    for (size_t i = end; i-- > 0;) {
      if (text_[i] != '"') continue;
      size_t backslashes = 0;
      while (backslashes < i && text_[i - 1 - backslashes] == '\\') ++backslashes;
      if (backslashes % 2 == 0) return i;
    }
    return end;
  }
  absl::Status Error(absl::string_view what, size_t offset) const {
    const TextPosition p = PositionInText(text_, offset);
    return absl::InvalidArgumentError(
        absl::StrCat(source_, ":", p.line, ":", p.column, ": ", what));
  }
  bool Fail(absl::string_view what, size_t offset) {
    if (error_.ok()) error_ = Error(what, offset);
    return false;
  }

  std::string_view text_;
  const std::string& source_;
  const ReadProgress* progress_;
  std::vector<Container> open_;
  std::optional<JsonValue> root_;
  absl::Status error_;
};

JsonValue JsonValue::Number(double v) {
  JsonValue j;
  j.type_ = Type::kNumber;
  j.number_ = v;
  return j;
}
JsonValue JsonValue::Bool(bool v) {
  JsonValue j;
  j.type_ = Type::kBool;
  j.bool_ = v;
  return j;
}
JsonValue JsonValue::String(std::string v) {
  JsonValue j;
  j.type_ = Type::kString;
  j.string_ = std::move(v);
  return j;
}

const JsonValue* JsonValue::Find(std::string_view key) const {
  for (const auto& [k, v] : members_)
    if (k == key) return &v;
  return nullptr;
}

absl::StatusOr<JsonValue> ParseJson(std::string_view text, const std::string& source) {
  ReadProgress progress;
  progress.begin = text.data();
  JsonTreeBuilder builder(text, source, &progress);
  bool parsed = false;
  try {
    parsed = Json::sax_parse(CountingIterator(text.data(), &progress),
                             CountingIterator(text.data() + text.size(), &progress), &builder);
  } catch (const std::exception& e) {  // nlohmann reports through parse_error; this is a backstop
    return absl::InvalidArgumentError(absl::StrCat(source, ": JSON: ", e.what()));
  }
  return builder.Finish(parsed);
}

std::string JsonEscape(std::string_view s) {
  return Json(std::string(s)).dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  if (v == 0) return "0";
  char buf[40];
  for (int prec = 6; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string IndentJson(std::string_view json) {
  std::string out;
  out.reserve(json.size() + json.size() / 2);
  int depth = 0;
  JsonStringTracker strings;
  auto newline = [&] {
    out += '\n';
    out.append(2 * static_cast<size_t>(std::max(depth, 0)), ' ');
  };
  auto next_token = [&](size_t i) {
    while (i < json.size() && std::isspace(static_cast<unsigned char>(json[i]))) ++i;
    return i;
  };
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (strings.InString(c)) {
      out += c;
      continue;
    }
    if (c == '{' || c == '[') {
      out += c;
      const size_t j = next_token(i + 1);
      if (j < json.size() && json[j] == (c == '{' ? '}' : ']')) {
        out += json[j];  // {} and [] stay on one line
        i = j;
      } else {
        ++depth;
        newline();
      }
    } else if (c == '}' || c == ']') {
      --depth;
      newline();
      out += c;
    } else if (c == ',') {
      out += c;
      newline();
    } else if (c == ':') {
      out += ": ";
    } else if (!std::isspace(static_cast<unsigned char>(c))) {
      out += c;
    }
  }
  if (!out.empty() && out.back() != '\n') out += '\n';
  return out;
}

void JsonWriter::Newline() {
  out_ += '\n';
  out_.append(2 * first_.size(), ' ');
}

void JsonWriter::BeforeValue() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.empty()) {
    if (!first_.back()) out_ += ',';
    first_.back() = false;
    Newline();
  }
}

void JsonWriter::BeginObject() {
  BeforeValue();
  out_ += '{';
  first_.push_back(true);
}
void JsonWriter::EndObject() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) Newline();
  out_ += '}';
  if (first_.empty()) out_ += '\n';
}
void JsonWriter::BeginArray() {
  BeforeValue();
  out_ += '[';
  first_.push_back(true);
}
void JsonWriter::EndArray() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) Newline();
  out_ += ']';
}
void JsonWriter::Key(std::string_view key) {
  BeforeValue();
  out_ += JsonEscape(key);
  out_ += ": ";
  after_key_ = true;
}
void JsonWriter::Number(double v) {
  BeforeValue();
  out_ += JsonNumber(v);
}
void JsonWriter::Int(long long v) {
  BeforeValue();
  out_ += std::to_string(v);
}
void JsonWriter::Bool(bool v) {
  BeforeValue();
  out_ += v ? "true" : "false";
}
void JsonWriter::String(std::string_view v) {
  BeforeValue();
  out_ += JsonEscape(v);
}
void JsonWriter::Null() {
  BeforeValue();
  out_ += "null";
}
void JsonWriter::NumberArray(std::string_view key, const std::vector<double>& values) {
  Key(key);
  BeforeValue();
  out_ += '[';
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out_ += ", ";
    out_ += JsonNumber(values[i]);
  }
  out_ += ']';
}

}  // namespace tactforce::io
