// The message definitions of the .lcm files, read at run time: a parser for the part of LCM's type
// language Bricklayer uses (package, struct, primitive and nested members, constant and variable array
// dimensions, constants) and LCM's type fingerprint, computed the way lcm-gen computes it. The
// exporters derive everything from these definitions (decoding, CSV columns, JSON Schemas), so a new
// .lcm file is exported without new code, and a message is recognised by its fingerprint alone.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace bricklayer::inspect {

class SchemaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One array dimension: a fixed size ("4") or the name of an earlier integer member ("num_blocks").
struct LcmDimension {
  bool variable = false;
  int64_t size = 0;          // when !variable
  std::string size_member;   // when variable
};

struct LcmMember {
  std::string name;
  std::string type;          // a primitive ("int32_t", "double", "string", "boolean", "byte", ...) or a
                             // struct's full name ("bricklayer.block_t")
  std::vector<LcmDimension> dimensions;  // empty: a scalar
  std::string comment;       // the comment on the member's line, without "//"
  bool is_primitive() const;
};

struct LcmConstant {
  std::string name;
  std::string type;
  std::string value;         // as written
};

struct LcmStruct {
  std::string package;
  std::string name;          // short name, e.g. "stack_t"
  std::string comment;       // the comment block before "struct"
  std::vector<LcmMember> members;
  std::vector<LcmConstant> constants;
  int64_t base_hash = 0;     // lcm-gen's hash of the members alone (nested types not included)
  std::string full_name() const { return package.empty() ? name : package + "." + name; }
};

bool is_lcm_primitive(const std::string& type);

// Parses one .lcm file's text (which may hold several structs). Throws SchemaError naming the file,
// line and what was expected.
std::vector<LcmStruct> parse_lcm(const std::string& text, const std::string& file_name);

// A set of parsed definitions, looked up by full name or by fingerprint.
class LcmTypeSet {
 public:
  void add(LcmStruct s);  // throws SchemaError on a duplicate name
  // Resolves nested type names and computes every fingerprint; throws SchemaError on an unknown type
  // or a variable dimension that does not name an earlier integer member.
  void finish();

  const LcmStruct* find(const std::string& full_name) const;
  const LcmStruct* find_by_fingerprint(int64_t fingerprint) const;
  int64_t fingerprint(const std::string& full_name) const;  // what lcm-gen's getHash() returns
  const std::map<std::string, LcmStruct>& structs() const { return structs_; }

 private:
  uint64_t compute_hash(const std::string& full_name, std::vector<std::string>& parents) const;
  std::map<std::string, LcmStruct> structs_;
  std::map<std::string, int64_t> fingerprints_;
  std::map<int64_t, std::string> by_fingerprint_;
};

// The definitions compiled into this program (every lcmtypes/*.lcm at build time).
const LcmTypeSet& builtin_types();

}  // namespace bricklayer::inspect
