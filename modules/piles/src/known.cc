#include "bricklayer/piles/known.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer::piles {

core::Stack harmonic_stack(int n, double block_height) {
  core::Stack stack;
  stack.block_height = block_height;
  // Right end of the block k-th from the top: sum_{j=k}^{n} 1/(2j).
  double right = 0.0;
  for (int k = n; k >= 1; --k) {
    right += 1.0 / (2.0 * k);
    stack.blocks.push_back({static_cast<int64_t>(n - k), n - k, right - 1.0});
  }
  return stack;
}

core::Stack column(const std::vector<double>& xs) {
  core::Stack s;
  for (size_t i = 0; i < xs.size(); ++i) s.blocks.push_back({static_cast<int64_t>(i), static_cast<int32_t>(i), xs[i]});
  return s;
}

core::Stack figure15_upper_alone() { return column({-1.2, -1.1, -0.5}); }
core::Stack figure15_both() { return column({-1.2, -0.6, 0.2}); }
core::Stack figure15_middle_alone() { return column({-1.2, -0.6, -0.7}); }

std::string default_fixture_path() { return std::string(BRICKLAYER_SOURCE_DIR) + "/tests/data/optimal-stacks.json"; }

std::vector<core::Stack> fixture_stacks(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the fixture file " + path);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::vector<core::Stack> out;
  for (const auto& s : j.at("stacks")) out.push_back(core::stack_from_json(s));
  return out;
}

core::Stack push_rightmost(core::Stack s, double dx) {
  size_t best = 0;
  for (size_t i = 1; i < s.blocks.size(); ++i) {
    if (s.blocks[i].x > s.blocks[best].x) best = i;
  }
  s.blocks[best].x += dx;
  return s;
}

}  // namespace bricklayer::piles
