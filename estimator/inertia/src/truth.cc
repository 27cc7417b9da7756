#include "tactforce/inertia/truth.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <variant>

#include "absl/strings/str_cat.h"

namespace tactforce::inertia {
namespace {

// A deliberately small JSON reader: one object whose values are numbers,
// strings, booleans, null or arrays of numbers. Nested objects and arrays of
// other things are skipped (parsed for syntax, values dropped).
struct Value {
  bool is_number = false;
  bool is_array = false;  // of numbers only
  bool other = false;     // string, bool, null, nested structure
  double number = 0;
  std::vector<double> array;
};

class Reader {
 public:
  Reader(const std::string& text, const std::string& source) : s_(text), src_(source) {}

  absl::StatusOr<std::map<std::string, Value>> Object() {
    std::map<std::string, Value> out;
    Ws();
    if (!Eat('{')) return Err("expected '{'");
    Ws();
    if (Eat('}')) return Finish(out);
    while (true) {
      Ws();
      absl::StatusOr<std::string> key = String();
      if (!key.ok()) return key.status();
      Ws();
      if (!Eat(':')) return Err("expected ':'");
      Ws();
      absl::StatusOr<Value> v = Any();
      if (!v.ok()) return v.status();
      out[*key] = *v;
      Ws();
      if (Eat(',')) continue;
      if (Eat('}')) break;
      return Err("expected ',' or '}'");
    }
    return Finish(out);
  }

 private:
  absl::StatusOr<std::map<std::string, Value>> Finish(std::map<std::string, Value>& out) {
    Ws();
    if (i_ != s_.size()) return Err("trailing characters after the object");
    return std::move(out);
  }
  absl::Status Err(const std::string& what) const {
    return absl::InvalidArgumentError(absl::StrCat(src_, ": JSON syntax error at byte ", i_, ": ", what));
  }
  void Ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool Eat(char c) {
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  absl::StatusOr<std::string> String() {
    if (!Eat('"')) return Err("expected a string");
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        if (++i_ >= s_.size()) break;
        const char e = s_[i_];
        if (e == 'u') {
          if (i_ + 4 >= s_.size()) return Err("bad \\u escape");
          out += '?';
          i_ += 4;
        } else {
          out += e == 'n' ? '\n' : e == 't' ? '\t' : e;
        }
        ++i_;
      } else {
        out += s_[i_++];
      }
    }
    if (!Eat('"')) return Err("unterminated string");
    return out;
  }
  absl::StatusOr<double> Number() {
    const char* begin = s_.c_str() + i_;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin) return Err("expected a value");
    i_ += end - begin;
    return v;
  }
  absl::StatusOr<Value> Any() {
    Value v;
    if (i_ >= s_.size()) return Err("unexpected end");
    const char c = s_[i_];
    if (c == '"') {
      absl::StatusOr<std::string> str = String();
      if (!str.ok()) return str.status();
      v.other = true;
      return v;
    }
    if (c == '{') {
      absl::Status st = Skip();
      if (!st.ok()) return st;
      v.other = true;
      return v;
    }
    if (c == '[') {
      ++i_;
      v.is_array = true;
      Ws();
      if (Eat(']')) return v;
      while (true) {
        Ws();
        absl::StatusOr<Value> e = Any();
        if (!e.ok()) return e.status();
        if (e->is_number) {
          v.array.push_back(e->number);
        } else {
          v.is_array = false;
          v.other = true;
        }
        Ws();
        if (Eat(',')) continue;
        if (Eat(']')) break;
        return Err("expected ',' or ']'");
      }
      return v;
    }
    for (const char* word : {"true", "false", "null"}) {
      const std::string w(word);
      if (s_.compare(i_, w.size(), w) == 0) {
        i_ += w.size();
        v.other = true;
        return v;
      }
    }
    absl::StatusOr<double> d = Number();
    if (!d.ok()) return d.status();
    v.is_number = true;
    v.number = *d;
    return v;
  }
  // Skips a nested object.
  absl::Status Skip() {
    int depth = 0;
    bool in_string = false;
    for (; i_ < s_.size(); ++i_) {
      const char c = s_[i_];
      if (in_string) {
        if (c == '\\') ++i_;
        else if (c == '"') in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if (c == '}' || c == ']') {
        if (--depth == 0) {
          ++i_;
          return absl::OkStatus();
        }
      }
    }
    return Err("unterminated object");
  }

  const std::string& s_;
  const std::string src_;
  size_t i_ = 0;
};

}  // namespace

absl::StatusOr<InertiaTruth> ParseTruthJson(const std::string& text, const std::string& source) {
  Reader reader(text, source);
  absl::StatusOr<std::map<std::string, Value>> obj = reader.Object();
  if (!obj.ok()) return obj.status();
  auto key_error = [&](const std::string& key, const std::string& what) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": key '", key, "': ", what));
  };
  auto array = [&](const std::string& key, size_t n, bool required,
                   std::vector<double>* out) -> absl::Status {
    auto it = obj->find(key);
    if (it == obj->end()) {
      return required ? absl::InvalidArgumentError(absl::StrCat(source, ": missing key '", key, "'"))
                      : absl::OkStatus();
    }
    if (!it->second.is_array || it->second.array.size() != n)
      return key_error(key, absl::StrCat("expected an array of ", n, " numbers"));
    for (double v : it->second.array)
      if (!std::isfinite(v)) return key_error(key, "not finite");
    *out = it->second.array;
    return absl::OkStatus();
  };
  InertiaTruth truth;
  auto m = obj->find("mass");
  if (m == obj->end()) return absl::InvalidArgumentError(absl::StrCat(source, ": missing key 'mass'"));
  if (!m->second.is_number || !std::isfinite(m->second.number)) return key_error("mass", "expected a number");
  if (!(m->second.number > 0)) return key_error("mass", "must be > 0");
  truth.params.mass = m->second.number;
  std::vector<double> com, inertia, g;
  if (absl::Status st = array("com", 3, true, &com); !st.ok()) return st;
  if (absl::Status st = array("inertia_com", 6, true, &inertia); !st.ok()) return st;
  if (absl::Status st = array("gravity_world", 3, false, &g); !st.ok()) return st;
  truth.params.com = Vec3(com[0], com[1], com[2]);
  truth.params.inertia_com =
      InertiaTensor::FromArray({inertia[0], inertia[1], inertia[2], inertia[3], inertia[4], inertia[5]});
  if (!g.empty()) truth.gravity_world = Vec3(g[0], g[1], g[2]);
  return truth;
}

absl::StatusOr<InertiaTruth> ReadTruthJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open"));
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParseTruthJson(buffer.str(), path);
}

std::string TruthToJson(const InertiaTruth& t) {
  char buf[64];
  auto num = [&](double v) {
    std::snprintf(buf, sizeof(buf), "%.17g", v);
    return std::string(buf);
  };
  const auto& p = t.params;
  const auto in = p.inertia_com.ToArray();
  std::string out = "{\n";
  out += "  \"mass\": " + num(p.mass) + ",\n";
  out += "  \"com\": [" + num(p.com.x()) + ", " + num(p.com.y()) + ", " + num(p.com.z()) + "],\n";
  out += "  \"inertia_com\": [";
  for (int i = 0; i < 6; ++i) out += (i ? ", " : "") + num(in[i]);
  out += "]";
  if (t.gravity_world) {
    const Vec3& g = *t.gravity_world;
    out += ",\n  \"gravity_world\": [" + num(g.x()) + ", " + num(g.y()) + ", " + num(g.z()) + "]";
  }
  out += "\n}\n";
  return out;
}

absl::Status WriteTruthJsonFile(const InertiaTruth& truth, const std::string& path) {
  std::ofstream f(path);
  if (!f) return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open for writing"));
  f << TruthToJson(truth);
  f.close();
  if (!f) return absl::InvalidArgumentError(absl::StrCat(path, ": write failed"));
  return absl::OkStatus();
}

}  // namespace tactforce::inertia
