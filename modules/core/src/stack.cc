// Stack validation and bricklayer-predict's JSON input format.
#include "bricklayer/core/stack.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "bricklayer/core/contacts.h"

namespace bricklayer::core {
namespace {

std::string block_name(const Stack& stack, size_t index) {
  std::ostringstream out;
  out << "block " << index << " (id " << stack.blocks[index].id << ")";
  return out.str();
}

void require_finite(double value, const std::string& what) {
  if (!std::isfinite(value)) throw StackError(what + " must be a finite number");
}

}  // namespace

void validate(const Stack& stack, const StackLimits& limits) {
  require_finite(stack.block_length, "block_length");
  require_finite(stack.block_height, "block_height");
  require_finite(stack.table_edge, "table_edge");
  if (stack.block_length <= 0) throw StackError("block_length must be positive");
  if (stack.block_height <= 0) throw StackError("block_height must be positive");
  if (stack.blocks.size() > limits.max_blocks) {
    throw StackError("too many blocks: " + std::to_string(stack.blocks.size()) + " (the maximum is " +
                     std::to_string(limits.max_blocks) + "); block " + std::to_string(limits.max_blocks) +
                     " (id " + std::to_string(stack.blocks[limits.max_blocks].id) + ") is the first one too many");
  }
  std::unordered_map<int64_t, size_t> seen;
  seen.reserve(stack.blocks.size());
  for (size_t i = 0; i < stack.blocks.size(); ++i) {
    const Block& b = stack.blocks[i];
    require_finite(b.x, block_name(stack, i) + ": x");
    // Normalised coordinates must stay finite too (x / block_length can overflow).
    require_finite((b.x - stack.table_edge) / stack.block_length, block_name(stack, i) + ": x relative to the edge");
    if (b.row < 0) throw StackError(block_name(stack, i) + ": row must be >= 0, got " + std::to_string(b.row));
    // Rows index per-row tables: a pile can never be taller than the block limit, and a row near
    // INT32_MAX would overflow "row + 1" (found by UBSan through test_reliability_hostile_input).
    if (static_cast<size_t>(b.row) >= limits.max_blocks)
      throw StackError(block_name(stack, i) + ": row " + std::to_string(b.row) + " is above the highest possible row (" +
                       std::to_string(limits.max_blocks - 1) + " with a limit of " +
                       std::to_string(limits.max_blocks) + " blocks)");
    auto [it, inserted] = seen.emplace(b.id, i);
    if (!inserted) {
      throw StackError(block_name(stack, i) + ": duplicate id, already used by block " + std::to_string(it->second));
    }
  }
  // Two blocks of one row may touch but not overlap by more than the contact tolerance.
  std::vector<size_t> order(stack.blocks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const Block& p = stack.blocks[a];
    const Block& q = stack.blocks[b];
    return p.row != q.row ? p.row < q.row : (p.x != q.x ? p.x < q.x : a < b);
  });
  for (size_t k = 1; k < order.size(); ++k) {
    const Block& p = stack.blocks[order[k - 1]];
    const Block& q = stack.blocks[order[k]];
    if (p.row != q.row) continue;
    const double overlap = (p.x + stack.block_length - q.x) / stack.block_length;
    if (overlap > kContactTolerance) {
      std::ostringstream out;
      out << block_name(stack, order[k]) << " overlaps " << block_name(stack, order[k - 1]) << " in row " << q.row
          << " by " << overlap << " block lengths";
      throw StackError(out.str());
    }
  }
}

Stack stack_from_json(const nlohmann::json& json, const StackLimits& limits) {
  if (!json.is_object()) throw StackError("a stack must be a JSON object with a \"blocks\" array");
  Stack stack;
  auto number = [](const nlohmann::json& value, const std::string& what) {
    if (!value.is_number()) throw StackError(what + " must be a number, got " + std::string(value.type_name()));
    return value.get<double>();
  };
  for (const auto& [key, value] : json.items()) {
    if (key == "block_length") {
      stack.block_length = number(value, "block_length");
    } else if (key == "block_height") {
      stack.block_height = number(value, "block_height");
    } else if (key == "table_edge") {
      stack.table_edge = number(value, "table_edge");
    } else if (key == "blocks") {
      // parsed below
    } else if (key == "name" || key == "comment" || key == "n" || key == "overhang") {
      // annotations (the fixture file carries n and overhang)
    } else {
      throw StackError("unknown key \"" + key +
                       "\" (expected block_length, block_height, table_edge, blocks, name, comment)");
    }
  }
  const auto blocks = json.find("blocks");
  if (blocks == json.end()) throw StackError("missing key \"blocks\"");
  if (!blocks->is_array()) throw StackError("\"blocks\" must be an array, got " + std::string(blocks->type_name()));
  if (blocks->size() > limits.max_blocks) {
    throw StackError("too many blocks: " + std::to_string(blocks->size()) + " (the maximum is " +
                     std::to_string(limits.max_blocks) + ")");
  }
  stack.blocks.reserve(blocks->size());
  for (size_t i = 0; i < blocks->size(); ++i) {
    const auto& item = (*blocks)[i];
    const std::string name = "block " + std::to_string(i);
    if (!item.is_object()) throw StackError(name + ": must be an object, got " + std::string(item.type_name()));
    Block block;
    block.id = static_cast<int64_t>(i);
    bool has_row = false;
    bool has_x = false;
    for (const auto& [key, value] : item.items()) {
      if (key == "id") {
        if (!value.is_number_integer()) {
          throw StackError(name + ": \"id\" must be an integer, got " + std::string(value.type_name()));
        }
        block.id = value.get<int64_t>();
      } else if (key == "row") {
        if (!value.is_number_integer()) {
          throw StackError(name + ": \"row\" must be an integer, got " + std::string(value.type_name()));
        }
        const int64_t row = value.get<int64_t>();
        if (row < 0 || row > 1'000'000) throw StackError(name + ": \"row\" must be in 0..1000000, got " + value.dump());
        block.row = static_cast<int32_t>(row);
        has_row = true;
      } else if (key == "x") {
        block.x = number(value, name + ": \"x\"");
        has_x = true;
      } else if (key == "comment") {
      } else {
        throw StackError(name + ": unknown key \"" + key + "\" (expected id, row, x)");
      }
    }
    if (!has_row) throw StackError(name + " (id " + std::to_string(block.id) + "): missing \"row\"");
    if (!has_x) throw StackError(name + " (id " + std::to_string(block.id) + "): missing \"x\"");
    stack.blocks.push_back(block);
  }
  validate(stack, limits);
  return stack;
}

Stack parse_stack(std::string_view text, const StackLimits& limits) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::exception& e) {
    std::string what = e.what();
    throw StackError("not valid JSON: " + what);
  }
  return stack_from_json(json, limits);
}

}  // namespace bricklayer::core
