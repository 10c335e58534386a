#include "bricklayer/inspect/table_layout.h"

#include <charconv>
#include <cmath>

#include "bricklayer/inspect/log_source.h"
#include "bricklayer/inspect/units.h"
#include "bricklayer/inspect/wall_clock.h"

namespace bricklayer::inspect {

namespace {

Json strip_binary(const Json& v) {
  if (v.is_binary()) return Json();
  if (v.is_object()) {
    Json out = Json::object();
    for (auto it = v.begin(); it != v.end(); ++it)
      if (!it.value().is_binary()) out[it.key()] = strip_binary(it.value());
    return out;
  }
  if (v.is_array()) {
    Json out = Json::array();
    for (const auto& e : v) out.push_back(strip_binary(e));
    return out;
  }
  return v;
}

}  // namespace

std::string cell_text(const Json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return v.dump();
  if (v.is_number_float()) {
    double d = v.get<double>();
    if (std::isnan(d)) return "nan";
    if (std::isinf(d)) return d > 0 ? "inf" : "-inf";
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, d);
    return std::string(buf, r.ptr);
  }
  if (v.is_string()) return v.get<std::string>();
  return strip_binary(v).dump();
}

std::string csv_quote(const std::string& cell) {
  if (cell.find_first_of(",\"\r\n") == std::string::npos) return cell;
  std::string out = "\"";
  for (char c : cell) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

TableLayout::TableLayout(const LcmTypeSet& types, const LcmStruct& type) {
  header_ = {"event", "log_utime_us", "log_utc"};
  for (const auto& m : type.members)
    if (!m.dimensions.empty() && m.dimensions[0].variable && !(m.type == "byte" && m.dimensions.size() == 1)) {
      row_length_member_ = m.dimensions[0].size_member;
      break;
    }
  if (!row_length_member_.empty()) header_.push_back("item_index");
  for (const auto& m : type.members) {
    bool row = !row_length_member_.empty() && !m.dimensions.empty() && m.dimensions[0].variable &&
               m.dimensions[0].size_member == row_length_member_;
    if (row) row_members_.push_back(m.name);
    add_member(types, type, m, "", {}, false, row);
  }
}

void TableLayout::add_member(const LcmTypeSet& types, const LcmStruct& owner, const LcmMember& m,
                             const std::string& prefix, std::vector<Step> path, bool per_item, bool row_member) {
  if (m.type == "byte" && !m.dimensions.empty()) return;  // image data: left out, its size stays
  size_t first = 0;
  if (row_member) {
    per_item = true;
    path.push_back({m.name, 0});
    first = 1;  // the row index is inserted when rows are made
  } else {
    path.push_back({m.name, 0});
  }
  // Any further variable dimension: one JSON cell.
  for (size_t d = first; d < m.dimensions.size(); ++d)
    if (m.dimensions[d].variable) {
      header_.push_back(prefix + column_name(owner.full_name(), m.name));
      columns_.push_back({path, Kind::kJsonText, per_item});
      return;
    }
  // Fixed dimensions: one column per element.
  std::vector<std::vector<size_t>> indices = {{}};
  for (size_t d = first; d < m.dimensions.size(); ++d) {
    std::vector<std::vector<size_t>> next;
    for (const auto& idx : indices)
      for (int64_t i = 0; i < m.dimensions[d].size; ++i) {
        auto e = idx;
        e.push_back(static_cast<size_t>(i));
        next.push_back(e);
      }
    indices = std::move(next);
  }
  std::string base = row_member && !m.is_primitive() ? prefix + m.name + "." : prefix;
  for (const auto& idx : indices) {
    std::vector<Step> p = path;
    std::string name = m.name;
    for (size_t i : idx) {
      p.push_back({"", i});
      name += "_" + std::to_string(i);
    }
    if (m.is_primitive()) {
      std::string unit = unit_suffix(owner.full_name(), m.name);
      header_.push_back(prefix + (unit.empty() ? name : name + "_" + unit));
      columns_.push_back({p, Kind::kValue, per_item});
      if (is_utime_name(m.name) && idx.empty()) {
        header_.push_back(prefix + m.name + "_utc");
        columns_.push_back({p, Kind::kUtcText, per_item});
      }
    } else {
      const LcmStruct* nested = types.find(m.type);
      std::string nested_prefix = row_member ? base : prefix + name + ".";
      for (const auto& nm : nested->members) add_member(types, *nested, nm, nested_prefix, p, per_item, false);
    }
  }
}

std::vector<std::vector<std::string>> TableLayout::rows(const LogEvent& event, const Json& message) const {
  size_t items = 0;
  if (!row_length_member_.empty()) {
    int64_t n = message.at(row_length_member_).get<int64_t>();
    items = n > 0 ? static_cast<size_t>(n) : 0;
  }
  std::vector<std::vector<std::string>> out;
  size_t count = std::max<size_t>(items, 1);
  out.reserve(count);
  for (size_t item = 0; item < count; ++item) {
    std::vector<std::string> row = {std::to_string(event.number), std::to_string(event.timestamp_us),
                                    utc_text(event.timestamp_us)};
    if (!row_length_member_.empty()) row.push_back(items ? std::to_string(item) : "");
    for (const auto& c : columns_) {
      const Json* v = &message;
      bool missing = false;
      for (size_t s = 0; s < c.path.size() && !missing; ++s) {
        const Step& step = c.path[s];
        if (!step.member.empty()) {
          v = &v->at(step.member);
          if (c.per_item && s == 0) {
            if (!items) missing = true;
            else v = &v->at(item);
          }
        } else {
          v = &v->at(step.index);
        }
      }
      if (missing) {
        row.emplace_back();
      } else if (c.kind == Kind::kUtcText) {
        row.push_back(utc_text(v->get<int64_t>()));
      } else if (c.kind == Kind::kJsonText) {
        row.push_back(strip_binary(*v).dump());
      } else {
        row.push_back(cell_text(*v));
      }
    }
    out.push_back(std::move(row));
  }
  return out;
}

}  // namespace bricklayer::inspect
