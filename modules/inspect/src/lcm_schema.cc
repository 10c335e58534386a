#include "bricklayer/inspect/lcm_schema.h"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace bricklayer::inspect {

namespace {

const char* const kPrimitives[] = {"int8_t", "int16_t", "int32_t", "int64_t", "float",
                                   "double", "string",  "boolean", "byte"};

struct Token {
  std::string text;
  int line = 0;
  bool comment = false;
};

std::vector<Token> tokenize(const std::string& text, const std::string& file) {
  std::vector<Token> out;
  int line = 1;
  size_t i = 0;
  while (i < text.size()) {
    char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      size_t end = text.find('\n', i);
      if (end == std::string::npos) end = text.size();
      out.push_back({text.substr(i + 2, end - i - 2), line, true});
      i = end;
    } else if (text.compare(i, 2, "/*") == 0) {
      size_t end = text.find("*/", i + 2);
      if (end == std::string::npos) throw SchemaError(file + ":" + std::to_string(line) + ": unterminated /* comment");
      std::string body = text.substr(i + 2, end - i - 2);
      out.push_back({body, line, true});
      line += static_cast<int>(std::count(body.begin(), body.end(), '\n'));
      i = end + 2;
    } else if (std::strchr("{}[];=,", c)) {
      out.push_back({std::string(1, c), line, false});
      ++i;
    } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '+') {
      size_t start = i;
      while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || std::strchr("_-.+", text[i]))) ++i;
      out.push_back({text.substr(start, i - start), line, false});
    } else {
      throw SchemaError(file + ":" + std::to_string(line) + ": unexpected character '" + std::string(1, c) + "'");
    }
  }
  return out;
}

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, std::string file) : file_(std::move(file)) {
    for (auto& t : tokens) (t.comment ? comments_ : tokens_).push_back(std::move(t));
  }

  std::vector<LcmStruct> parse() {
    std::vector<LcmStruct> out;
    std::string package;
    while (pos_ < tokens_.size()) {
      const Token& t = next();
      if (t.text == "package") {
        package = expect_identifier_path("a package name");
        expect(";");
      } else if (t.text == "struct") {
        out.push_back(parse_struct(package, t.line));
      } else {
        fail(t, "expected 'package' or 'struct', found '" + t.text + "'");
      }
    }
    return out;
  }

 private:
  [[noreturn]] void fail(const Token& t, const std::string& what) const {
    throw SchemaError(file_ + ":" + std::to_string(t.line) + ": " + what);
  }
  const Token& next() {
    if (pos_ >= tokens_.size()) {
      Token end{"", tokens_.empty() ? 1 : tokens_.back().line, false};
      fail(end, "unexpected end of file");
    }
    return tokens_[pos_++];
  }
  const Token& peek() {
    if (pos_ >= tokens_.size()) return next();  // throws
    return tokens_[pos_];
  }
  void expect(const std::string& text) {
    const Token& t = next();
    if (t.text != text) fail(t, "expected '" + text + "', found '" + t.text + "'");
  }
  std::string expect_identifier_path(const std::string& what) {
    const Token& t = next();
    std::string s = t.text;
    size_t start = 0;
    while (true) {
      size_t dot = s.find('.', start);
      if (!is_identifier(s.substr(start, dot == std::string::npos ? std::string::npos : dot - start)))
        fail(t, "expected " + what + ", found '" + t.text + "'");
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    return s;
  }
  std::string comments_on_line(int line) const {
    std::string out;
    for (const auto& c : comments_)
      if (c.line == line) out += (out.empty() ? "" : " ") + trim(c.text);
    return out;
  }
  std::string comments_before(int line) const {
    // The comment block that ends on the line just above `line`.
    std::vector<std::string> parts;
    int want = line - 1;
    for (auto it = comments_.rbegin(); it != comments_.rend(); ++it) {
      if (it->line > want) continue;
      if (it->line < want) break;
      parts.push_back(trim(it->text));
      --want;
    }
    std::reverse(parts.begin(), parts.end());
    std::string out;
    for (const auto& p : parts) out += (out.empty() ? "" : " ") + p;
    return out;
  }

  LcmStruct parse_struct(const std::string& package, int line) {
    LcmStruct s;
    s.package = package;
    s.comment = comments_before(line);
    s.name = expect_identifier_path("a struct name");
    if (s.name.find('.') != std::string::npos) fail(tokens_[pos_ - 1], "a struct name has no package part here");
    expect("{");
    while (peek().text != "}") {
      const Token& first = next();
      if (first.text == "const") {
        std::string type = expect_identifier_path("a constant's type");
        if (!is_lcm_primitive(type) || type == "string" || type == "byte")
          fail(first, "constant of type '" + type + "': only numeric types can be constants");
        while (true) {
          LcmConstant c;
          c.type = type;
          c.name = expect_identifier_path("a constant's name");
          expect("=");
          c.value = next().text;
          s.constants.push_back(c);
          const Token& sep = next();
          if (sep.text == ";") break;
          if (sep.text != ",") fail(sep, "expected ',' or ';' after a constant, found '" + sep.text + "'");
        }
        continue;
      }
      --pos_;
      LcmMember m;
      m.type = expect_identifier_path("a member's type");
      if (!is_lcm_primitive(m.type) && m.type.find('.') == std::string::npos && !package.empty())
        m.type = package + "." + m.type;
      m.name = expect_identifier_path("a member's name");
      if (!is_identifier(m.name)) fail(tokens_[pos_ - 1], "a member name is a plain identifier");
      while (peek().text == "[") {
        next();
        const Token& size = next();
        LcmDimension d;
        if (!size.text.empty() && std::all_of(size.text.begin(), size.text.end(), ::isdigit)) {
          d.size = std::stoll(size.text);
        } else if (is_identifier(size.text)) {
          d.variable = true;
          d.size_member = size.text;
        } else {
          fail(size, "expected an array size (a number or an earlier member), found '" + size.text + "'");
        }
        m.dimensions.push_back(d);
        expect("]");
      }
      const Token& semi = next();
      if (semi.text != ";") fail(semi, "expected ';' after member '" + m.name + "', found '" + semi.text + "'");
      m.comment = comments_on_line(semi.line);
      for (const auto& other : s.members)
        if (other.name == m.name) fail(semi, "member '" + m.name + "' declared twice");
      s.members.push_back(std::move(m));
    }
    next();  // }
    return s;
  }

  std::string file_;
  std::vector<Token> tokens_;
  std::vector<Token> comments_;
  size_t pos_ = 0;
};

// lcm-gen's hash of one struct's own members (lcmgen.c, lcm_struct_hash): member names, primitive type
// names and dimensions; the struct's name and nested types' contents are not part of it.
int64_t hash_update(int64_t v, char c) {
  uint64_t u = static_cast<uint64_t>(v);
  uint64_t mixed = (u << 8) ^ static_cast<uint64_t>(v >> 55);  // v >> 55 is an arithmetic shift, as in C
  return static_cast<int64_t>(mixed + static_cast<uint64_t>(static_cast<int64_t>(c)));
}

int64_t hash_string_update(int64_t v, const std::string& s) {
  v = hash_update(v, static_cast<char>(s.size()));
  for (char c : s) v = hash_update(v, c);
  return v;
}

int64_t base_hash(const LcmStruct& s) {
  int64_t v = 0x12345678;
  for (const auto& m : s.members) {
    v = hash_string_update(v, m.name);
    if (m.is_primitive()) v = hash_string_update(v, m.type);
    v = hash_update(v, static_cast<char>(m.dimensions.size()));
    for (const auto& d : m.dimensions) {
      v = hash_update(v, d.variable ? 1 : 0);
      v = hash_string_update(v, d.variable ? d.size_member : std::to_string(d.size));
    }
  }
  return v;
}

}  // namespace

bool is_lcm_primitive(const std::string& type) {
  return std::find(std::begin(kPrimitives), std::end(kPrimitives), type) != std::end(kPrimitives);
}

bool LcmMember::is_primitive() const { return is_lcm_primitive(type); }

std::vector<LcmStruct> parse_lcm(const std::string& text, const std::string& file_name) {
  Parser parser(tokenize(text, file_name), file_name);
  std::vector<LcmStruct> out = parser.parse();
  for (auto& s : out) s.base_hash = base_hash(s);
  return out;
}

void LcmTypeSet::add(LcmStruct s) {
  std::string name = s.full_name();
  if (structs_.count(name)) throw SchemaError("type " + name + " is defined twice");
  structs_.emplace(name, std::move(s));
}

uint64_t LcmTypeSet::compute_hash(const std::string& full_name, std::vector<std::string>& parents) const {
  // The generated _computeHash(): a type already on the path contributes 0 (recursive types).
  if (std::find(parents.begin(), parents.end(), full_name) != parents.end()) return 0;
  const LcmStruct& s = structs_.at(full_name);
  parents.push_back(full_name);
  uint64_t hash = static_cast<uint64_t>(s.base_hash);
  for (const auto& m : s.members)
    if (!m.is_primitive()) hash += compute_hash(m.type, parents);
  parents.pop_back();
  return (hash << 1) + ((hash >> 63) & 1);
}

void LcmTypeSet::finish() {
  for (const auto& [name, s] : structs_) {
    for (size_t i = 0; i < s.members.size(); ++i) {
      const LcmMember& m = s.members[i];
      if (!m.is_primitive() && !structs_.count(m.type))
        throw SchemaError(name + "." + m.name + ": unknown type " + m.type);
      for (const auto& d : m.dimensions) {
        if (!d.variable) continue;
        auto it = std::find_if(s.members.begin(), s.members.begin() + static_cast<long>(i),
                               [&](const LcmMember& o) { return o.name == d.size_member; });
        if (it == s.members.begin() + static_cast<long>(i) || !it->dimensions.empty() ||
            !(it->type == "int8_t" || it->type == "int16_t" || it->type == "int32_t" || it->type == "int64_t"))
          throw SchemaError(name + "." + m.name + ": array size '" + d.size_member +
                            "' must be an earlier integer member");
      }
    }
  }
  fingerprints_.clear();
  by_fingerprint_.clear();
  for (const auto& [name, s] : structs_) {
    std::vector<std::string> parents;
    int64_t fp = static_cast<int64_t>(compute_hash(name, parents));
    fingerprints_[name] = fp;
    by_fingerprint_[fp] = name;
  }
}

const LcmStruct* LcmTypeSet::find(const std::string& full_name) const {
  auto it = structs_.find(full_name);
  return it == structs_.end() ? nullptr : &it->second;
}

const LcmStruct* LcmTypeSet::find_by_fingerprint(int64_t fingerprint) const {
  auto it = by_fingerprint_.find(fingerprint);
  return it == by_fingerprint_.end() ? nullptr : find(it->second);
}

int64_t LcmTypeSet::fingerprint(const std::string& full_name) const {
  auto it = fingerprints_.find(full_name);
  if (it == fingerprints_.end()) throw SchemaError("no type " + full_name);
  return it->second;
}

}  // namespace bricklayer::inspect
