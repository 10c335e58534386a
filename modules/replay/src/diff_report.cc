#include "bricklayer/replay/diff_report.h"

#include <cmath>
#include <cstdio>
#include <regex>
#include <set>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/replay/checker.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::replay {
namespace {

const char* state_name(int s) {
  switch (s) {
    case block_prediction_t::STATE_STABLE: return "stable";
    case block_prediction_t::STATE_MOVING: return "moving";
    case block_prediction_t::STATE_CAUSE: return "cause";
  }
  return "?";
}

std::string generic(const std::string& path) {
  static const std::regex index(R"(\[\d+\])");
  return std::regex_replace(path, index, "[]");
}

// A block moved when its x differs by more than this (block lengths): vision's p95 error is 0.002.
constexpr double kMovedBlockLengths = 0.001;

}  // namespace

DiffReport::DiffReport(const MessageDiff& diff, std::string a, std::string b, int64_t start, size_t max_listed)
    : diff_(diff),
      a_(std::move(a)),
      b_(std::move(b)),
      start_(start),
      max_listed_(max_listed),
      matcher_(
          diff, [this](const Pair& p) { pair(p); }, [this](const MessageKey&, int side) { ++only_[side]; }) {}

void DiffReport::add(int side, const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
  ++outputs_[side];
  matcher_.add(side, channel, bytes, utime);
}

void DiffReport::pair(const Pair& p) {
  ++pairs_;
  auto& ch = per_channel_[p.key.channel];
  ++ch.first;
  if (p.a == p.b) return;
  const auto d = diff_.differences(p.a, p.b);
  if (d.empty()) return;
  ++differing_;
  ++ch.second;
  std::set<std::string> paths;
  for (const auto& f : d) paths.insert(generic(f.path));
  for (const auto& path : paths) ++fields_[p.key.channel][path];
  if (first_.size() < max_listed_)
    first_.push_back(p.key.channel + " at " + Checker::when(p.key.utime, start_) +
                     (p.key.frame_number >= 0 ? " frame " + std::to_string(p.key.frame_number) : "") + ": " +
                     MessageDiff::describe(d, a_, b_, 4));
  const std::string type = diff_.type_of(p.a.data(), p.a.size());
  if (type == "prediction_t") predictions(p);
  if (type == "stack_t") stacks(p);
}

void DiffReport::predictions(const Pair& p) {
  const auto a = runtime::decode<prediction_t>(p.a), b = runtime::decode<prediction_t>(p.b);
  if (!a || !b) return;
  ++verdict_messages_;
  if (a->balanced != b->balanced) ++balanced_flips_;
  std::string changes;
  // Blocks are in the stack's order on both sides (the same input); matched by id to be sure.
  for (const auto& ba : a->blocks) {
    for (const auto& bb : b->blocks) {
      if (bb.id != ba.id || bb.state == ba.state) continue;
      ++verdict_changes_[{ba.state, bb.state}];
      changes += (changes.empty() ? "" : ", ") + std::string("block ") + std::to_string(ba.id) + " " + state_name(ba.state) +
                 " -> " + state_name(bb.state);
    }
  }
  if (!changes.empty() && verdict_frames_.size() < max_listed_)
    verdict_frames_.push_back(Checker::when(p.key.utime, start_) + " frame " + std::to_string(p.key.frame_number) + " (" +
                              std::to_string(a->num_blocks) + " blocks): " + changes);
}

void DiffReport::stacks(const Pair& p) {
  const auto a = runtime::decode<stack_t>(p.a), b = runtime::decode<stack_t>(p.b);
  if (!a || !b) return;
  ++block_messages_;
  std::string changes;
  auto find = [](const stack_t& s, int64_t id) -> const block_t* {
    for (const auto& bl : s.blocks)
      if (bl.id == id) return &bl;
    return nullptr;
  };
  for (const auto& ba : a->blocks) {
    const block_t* bb = find(*b, ba.id);
    char text[96];
    if (!bb) {
      ++blocks_only_[0];
      std::snprintf(text, sizeof text, "block %lld only in %s (row %d, x %.3f)", static_cast<long long>(ba.id), a_.c_str(), ba.row, ba.x);
    } else if (bb->row != ba.row) {
      ++blocks_row_;
      std::snprintf(text, sizeof text, "block %lld row %d -> %d", static_cast<long long>(ba.id), ba.row, bb->row);
    } else if (std::fabs(bb->x - ba.x) > kMovedBlockLengths) {
      ++blocks_moved_;
      std::snprintf(text, sizeof text, "block %lld x %.4f -> %.4f", static_cast<long long>(ba.id), ba.x, bb->x);
    } else {
      continue;
    }
    changes += (changes.empty() ? "" : ", ") + std::string(text);
  }
  for (const auto& bb : b->blocks) {
    if (find(*a, bb.id)) continue;
    ++blocks_only_[1];
    char text[96];
    std::snprintf(text, sizeof text, "block %lld only in %s (row %d, x %.3f)", static_cast<long long>(bb.id), b_.c_str(), bb.row, bb.x);
    changes += (changes.empty() ? "" : ", ") + std::string(text);
  }
  if (!changes.empty() && block_frames_.size() < max_listed_)
    block_frames_.push_back(Checker::when(p.key.utime, start_) + " frame " + std::to_string(p.key.frame_number) + ": " + changes);
}

void DiffReport::print(std::ostream& out) const {
  out << "outputs: A " << outputs_[0] << ", B " << outputs_[1] << "; " << pairs_ << " pairs, " << pairs_ - differing_
      << " identical, " << differing_ << " differ; " << only_[0] << " only in A, " << only_[1] << " only in B\n";
  out << "\n| channel | pairs | differ | fields that differ (messages) |\n|---|---|---|---|\n";
  for (const auto& [channel, counts] : per_channel_) {
    std::string fields;
    if (auto it = fields_.find(channel); it != fields_.end())
      for (const auto& [path, n] : it->second) fields += (fields.empty() ? "" : ", ") + path + " " + std::to_string(n);
    out << "| " << channel << " | " << counts.first << " | " << counts.second << " | " << (fields.empty() ? "-" : fields)
        << " |\n";
  }
  if (verdict_messages_ > 0) {
    out << "\nverdicts: " << verdict_messages_ << " predictions differ, balanced flipped in " << balanced_flips_
        << "; block states A -> B:\n";
    for (const auto& [change, n] : verdict_changes_)
      out << "  " << state_name(change.first) << " -> " << state_name(change.second) << ": " << n << "\n";
    for (const auto& f : verdict_frames_) out << "  " << f << "\n";
  }
  if (block_messages_ > 0) {
    out << "\nblocks: " << block_messages_ << " stacks differ; " << blocks_only_[0] << " blocks only in A, "
        << blocks_only_[1] << " only in B, " << blocks_moved_ << " moved by more than " << kMovedBlockLengths
        << " block lengths, " << blocks_row_ << " in another row\n";
    for (const auto& f : block_frames_) out << "  " << f << "\n";
  }
  if (!first_.empty()) {
    out << "\nfirst divergences:\n";
    for (const auto& f : first_) out << "  " << f << "\n";
  }
}

}  // namespace bricklayer::replay
