// JSON for tactforce's flat files (sensor model JSON, audit report.json,
// inertia truth files, trajectory JSON), read and written through Debian's
// nlohmann-json3 (the API messages use protobuf's JSON mapping instead).
// JsonEscape is also the CLI's string quoter.
//
// Reader: RFC 8259 JSON (objects, arrays, strings with \uXXXX escapes
// including surrogate pairs, numbers, true/false/null), UTF-8. Every value
// knows the line it starts on, object members keep their file order, and a
// duplicate key or nesting deeper than kMaxJsonDepth is an error. Errors are
// InvalidArgument naming the source, line and column (bytes), compiler style:
//   "m.json:1:9: expected ':', found number literal '1'"
// Writer: JsonWriter emits pretty-printed JSON; non-finite numbers are written
// as null (JSON has no NaN/Infinity).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace tactforce::io {

// At most this many objects and arrays open at once ([[1]] has two).
inline constexpr int kMaxJsonDepth = 64;

class JsonValue {
 public:
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };

  JsonValue() = default;
  static JsonValue Number(double v);
  static JsonValue Bool(bool v);
  static JsonValue String(std::string v);

  Type type() const { return type_; }
  bool is_null() const { return type_ == Type::kNull; }
  bool is_number() const { return type_ == Type::kNumber; }
  bool is_string() const { return type_ == Type::kString; }
  bool is_bool() const { return type_ == Type::kBool; }
  bool is_object() const { return type_ == Type::kObject; }
  bool is_array() const { return type_ == Type::kArray; }

  double number() const { return number_; }  // integers too (exact up to 2^53)
  bool boolean() const { return bool_; }
  const std::string& string() const { return string_; }  // UTF-8
  const std::vector<JsonValue>& array() const { return array_; }
  // Object members in file order (keys unique; a duplicate key is an error).
  const std::vector<std::pair<std::string, JsonValue>>& members() const { return members_; }
  const JsonValue* Find(std::string_view key) const;  // nullptr when absent
  int line() const { return line_; }  // 1-based line where it starts; 0 if built in code
  // 1-based byte column of its first byte (a string's opening quote, a
  // container's '{' / '['); 0 if built in code.
  int column() const { return column_; }
  struct Position {
    int line = 0, column = 0;  // 1-based; 0 if built in code
  };
  // Where the key of members()[i] starts (its opening quote).
  Position KeyPosition(size_t i) const {
    return i < key_positions_.size() ? key_positions_[i] : Position{};
  }

 private:
  friend class JsonTreeBuilder;  // json.cc: builds values from the parser's events
  Type type_ = Type::kNull;
  double number_ = 0;
  bool bool_ = false;
  std::string string_;
  std::vector<JsonValue> array_;
  std::vector<std::pair<std::string, JsonValue>> members_;
  std::vector<Position> key_positions_;  // parallel to members_
  int line_ = 0;
  int column_ = 0;
};

// The one JSON document in `text`; `source` names it in errors (a file name).
absl::StatusOr<JsonValue> ParseJson(std::string_view text, const std::string& source);

// Streaming pretty writer (two-space indent, one member or element a line,
// NumberArray on one line). Usage:
//   JsonWriter w; w.BeginObject(); w.Key("a"); w.Number(1); w.EndObject();
//   std::string s = w.str();   // "{\n  \"a\": 1\n}\n"
class JsonWriter {
 public:
  void BeginObject();
  void EndObject();
  void BeginArray();
  void EndArray();
  void Key(std::string_view key);
  void Number(double v);
  void Int(long long v);
  void Bool(bool v);
  void String(std::string_view v);
  void Null();
  // Convenience: Key(k) + value.
  void Field(std::string_view key, double v) {
    Key(key);
    Number(v);
  }
  void Field(std::string_view key, std::string_view v) {
    Key(key);
    String(v);
  }
  void Field(std::string_view key, const char* v) {
    Key(key);
    String(v);
  }
  void FieldBool(std::string_view key, bool v) {
    Key(key);
    Bool(v);
  }
  void FieldInt(std::string_view key, long long v) {
    Key(key);
    Int(v);
  }
  // Arrays of numbers on one line.
  void NumberArray(std::string_view key, const std::vector<double>& values);
  const std::string& str() const { return out_; }

 private:
  void BeforeValue();
  void Newline();
  std::string out_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

// `json` (valid JSON text, compact or indented any way) in the one layout
// every command prints, JsonWriter's: two spaces per level, one member or
// element a line, `"key": value`, empty containers as {} and [], a final
// newline. Only whitespace outside strings changes (numbers, key order and
// escapes are kept byte for byte).
std::string IndentJson(std::string_view json);

// Follows JSON text one character at a time and tells which characters are
// inside a string literal, so scanners of raw JSON text (indenters, list
// splitters, layout checks) can skip brackets and commas in strings.
class JsonStringTracker {
 public:
  // True when `c`, the next character of the text, belongs to a string,
  // its quotes and escapes included.
  bool InString(char c) {
    if (!in_string_) return in_string_ = (c == '"');
    if (escaped_) {
      escaped_ = false;
    } else if (c == '\\') {
      escaped_ = true;
    } else if (c == '"') {
      in_string_ = false;
    }
    return true;
  }

 private:
  bool in_string_ = false;
  bool escaped_ = false;
};

// `s` as a quoted JSON string (nlohmann's escaping: \" \\ \b \f \n \r \t,
// other control characters as \u00XX; invalid UTF-8 becomes U+FFFD).
std::string JsonEscape(std::string_view s);
// Shortest round-trip formatting of a double ("%.17g" trimmed: 0.1, 1e-05,
// 2500, 1e+06); "null" if not finite.
std::string JsonNumber(double v);

}  // namespace tactforce::io
