#include "bricklayer/study/study_log.h"

#include <memory>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/study/channels.h"

namespace bricklayer::study {
namespace {

template <typename T>
bool decode(const lcm::LogEvent& event, T& msg) {
  return msg.decode(event.data, 0, static_cast<int>(event.datalen)) >= 0;
}

}  // namespace

LogReadCounts read_study_log(const std::string& path, StudyCollector& collector) {
  auto log = std::make_unique<lcm::LogFile>(path, "r");
  if (!log->good()) throw std::runtime_error(path + ": cannot be opened as an LCM log");
  const std::string session = channel(kSessionChannel);
  const std::string trial = channel(kTrialChannel);
  const std::string answer = channel(kAnswerChannel);
  LogReadCounts counts;
  auto bad = [&](const lcm::LogEvent& e) {
    ++counts.bad_messages;
    if (counts.errors.size() < 20) {
      counts.errors.push_back(path + ": event " + std::to_string(e.eventnum) + " on " + e.channel + " does not decode (" +
                              std::to_string(e.datalen) + " bytes)");
    }
  };
  while (const lcm::LogEvent* e = log->readNextEvent()) {
    ++counts.events;
    if (e->channel == session) {
      bricklayer::study_session_t msg{};
      if (!decode(*e, msg)) { bad(*e); continue; }
      collector.add(msg);
    } else if (e->channel == trial) {
      bricklayer::study_trial_t msg{};
      if (!decode(*e, msg)) { bad(*e); continue; }
      collector.add(msg);
    } else if (e->channel == answer) {
      bricklayer::study_answer_t msg{};
      if (!decode(*e, msg)) { bad(*e); continue; }
      collector.add(msg);
    } else {
      continue;
    }
    ++counts.study_messages;
  }
  return counts;
}

}  // namespace bricklayer::study
