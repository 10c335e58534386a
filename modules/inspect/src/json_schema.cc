#include "bricklayer/inspect/json_schema.h"

#include <cmath>

#include "bricklayer/inspect/units.h"

namespace bricklayer::inspect {

namespace {

Json primitive_schema(const std::string& t) {
  auto range = [](int64_t lo, int64_t hi) { return Json{{"type", "integer"}, {"minimum", lo}, {"maximum", hi}}; };
  if (t == "int8_t") return range(-128, 127);
  if (t == "int16_t") return range(-32768, 32767);
  if (t == "int32_t") return range(INT32_MIN, INT32_MAX);
  if (t == "int64_t") return Json{{"type", "integer"}};
  if (t == "byte") return range(0, 255);
  if (t == "boolean") return Json{{"type", "boolean"}};
  if (t == "string") return Json{{"type", "string"}};
  return Json{{"type", Json::array({"number", "null"})}};  // float, double: null stands for NaN / infinity
}

Json struct_schema(const LcmTypeSet& types, const LcmStruct& s);

Json member_schema(const LcmTypeSet& types, const LcmStruct& owner, const LcmMember& m, size_t dim) {
  if (dim == m.dimensions.size()) return m.is_primitive() ? primitive_schema(m.type) : struct_schema(types, *types.find(m.type));
  Json a = {{"type", "array"}, {"items", member_schema(types, owner, m, dim + 1)}};
  const LcmDimension& d = m.dimensions[dim];
  if (!d.variable) {
    a["minItems"] = d.size;
    a["maxItems"] = d.size;
  }
  return a;
}

Json struct_schema(const LcmTypeSet& types, const LcmStruct& s) {
  Json properties = Json::object();
  Json required = Json::array();
  bool image = s.full_name() == kImageType;
  for (const auto& m : s.members) {
    if (image && m.name == "data") continue;
    Json p = member_schema(types, s, m, 0);
    std::string description = m.comment;
    std::string unit = unit_suffix(s.full_name(), m.name);
    if (!unit.empty()) description += (description.empty() ? "" : " ") + std::string("[unit: ") + unit + "]";
    for (const auto& d : m.dimensions)
      if (d.variable) description += (description.empty() ? "" : " ") + std::string("[length: ") + d.size_member + "]";
    if (!description.empty()) p["description"] = description;
    properties[m.name] = p;
    required.push_back(m.name);
  }
  std::string description = s.comment;
  if (image) description += " The bytes of `data` are on the topic CHANNEL/image as a foxglove image, not here.";
  if (!s.constants.empty()) {
    description += " Constants:";
    for (const auto& c : s.constants) description += " " + c.name + " = " + c.value + ";";
  }
  Json out = {{"title", s.full_name()}, {"type", "object"}};
  if (!description.empty()) out["description"] = description;
  out["properties"] = properties;
  out["required"] = required;
  out["additionalProperties"] = false;
  return out;
}

Json to_mcap(const LcmTypeSet& types, const std::string& type, const Json& v) {
  if (v.is_binary()) {
    Json a = Json::array();
    for (uint8_t b : v.get_binary()) a.push_back(b);
    return a;
  }
  if (v.is_number_float() && !std::isfinite(v.get<double>())) return nullptr;
  if (v.is_array()) {
    Json a = Json::array();
    for (const auto& e : v) a.push_back(to_mcap(types, type, e));
    return a;
  }
  if (v.is_object()) {
    const LcmStruct* s = types.find(type);
    Json o = Json::object();
    for (const auto& m : s->members) {
      if (s->full_name() == kImageType && m.name == "data") continue;
      o[m.name] = to_mcap(types, m.type, v.at(m.name));
    }
    return o;
  }
  return v;
}

}  // namespace

Json json_schema(const LcmTypeSet& types, const LcmStruct& type) {
  Json s = struct_schema(types, type);
  Json out = {{"$schema", "http://json-schema.org/draft-07/schema#"}};
  for (auto it = s.begin(); it != s.end(); ++it) out[it.key()] = it.value();
  return out;
}

Json mcap_json(const LcmTypeSet& types, const LcmStruct& type, const Json& message) {
  return to_mcap(types, type.full_name(), message);
}

}  // namespace bricklayer::inspect
