#include "bricklayer/replay/replay.h"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>

namespace bricklayer::replay {

std::string ReplayReport::summary() const {
  std::ostringstream out;
  out << compared << " compared, " << mismatches << " mismatches (" << events << " log events, " << inputs
      << " inputs fed, " << rejected_inputs << " rejected, " << outputs << " outputs computed, " << not_in_log
      << " not in the log, " << orphans << " recorded outputs without their input)";
  return out.str();
}

ReplayReport replay_log(const std::string& path, ReplayModule& module, bool check, std::ostream& out) {
  auto log = std::make_unique<lcm::LogFile>(path, "r");
  if (!log->good()) throw std::runtime_error("cannot read LCM log '" + path + "'");

  const auto in_channels = module.input_channels();
  const auto out_channels = module.output_channels();
  auto is_in = [&](const std::string& c) { return std::find(in_channels.begin(), in_channels.end(), c) != in_channels.end(); };
  auto is_out = [&](const std::string& c) { return std::find(out_channels.begin(), out_channels.end(), c) != out_channels.end(); };

  ReplayReport report;
  std::vector<std::pair<std::string, Bytes>> inputs;
  struct Recorded {
    std::vector<Bytes> versions;  // the same input may have been answered more than once
    bool matched = false;
  };
  std::map<MessageKey, Recorded> recorded;
  while (const lcm::LogEvent* e = log->readNextEvent()) {
    ++report.events;
    const auto* data = static_cast<const uint8_t*>(e->data);
    if (is_in(e->channel)) {
      inputs.emplace_back(e->channel, Bytes(data, data + e->datalen));
    } else if (is_out(e->channel)) {
      Bytes bytes(data, data + e->datalen);
      module.observe_recorded(e->channel, bytes);
      auto key = module.key(e->channel, bytes);
      if (!key) {
        ++report.mismatches;
        out << "MISMATCH " << e->channel << " event " << e->eventnum << ": recorded output does not decode\n";
        continue;
      }
      recorded[*key].versions.push_back(std::move(bytes));
    }
  }

  for (const auto& [channel, bytes] : inputs) {
    ++report.inputs;
    auto outputs = module.feed(channel, bytes);
    if (!outputs) {
      ++report.rejected_inputs;
      continue;
    }
    for (const auto& o : *outputs) {
      ++report.outputs;
      if (!check) continue;
      auto key = module.key(o.channel, o.bytes);
      if (!key) throw std::logic_error("replay: the module produced an output it cannot decode on " + o.channel);
      auto it = recorded.find(*key);
      if (it == recorded.end()) {
        ++report.not_in_log;
        continue;
      }
      ++report.compared;
      it->second.matched = true;
      const auto& versions = it->second.versions;
      if (std::find(versions.begin(), versions.end(), o.bytes) != versions.end()) continue;
      ++report.mismatches;
      out << "MISMATCH " << o.channel << " utime " << key->utime << " frame " << key->frame_number << ": "
          << module.describe_difference(o.channel, versions.front(), o.bytes) << "\n";
    }
  }
  if (check) {
    for (const auto& [key, rec] : recorded) {
      if (rec.matched) continue;
      ++report.orphans;
      if (report.orphans <= 10)
        out << "note: recorded " << key.channel << " utime " << key.utime << " frame " << key.frame_number
            << " has no input in this log\n";
    }
  }
  return report;
}

}  // namespace bricklayer::replay
