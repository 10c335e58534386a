// What the replay tests share: bricklayer-replay run to its end, the counts its --check prints, and a
// copy of a log with one event tampered with.
#pragma once

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <regex>
#include <string>
#include <vector>

#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "harness/scratch.h"

namespace bricklayer::test {

// bricklayer-replay with args (and --no-progress), killed after timeout.
inline harness::Ran replay(std::vector<std::string> args, std::chrono::milliseconds timeout = std::chrono::seconds(120)) {
  args.push_back("--no-progress");
  return harness::run_program("bricklayer-replay", std::move(args), timeout);
}

// "N compared, 0 mismatches" -> N; -1 when there were mismatches or no summary.
inline int64_t compared_ok(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"((\d+) compared, 0 mismatches)")) ? std::stoll(m[1]) : -1;
}

// "compared per channel: BL_PROJECTOR 80 BL_ROUND 12 ..." -> the count for one channel (0 if absent).
inline int64_t compared_on(const std::string& out, const std::string& ch) {
  std::smatch m;
  return std::regex_search(out, m, std::regex("compared per channel:.* " + ch + R"( (\d+))")) ? std::stoll(m[1]) : 0;
}

// A copy of the log `from` (as dir/name) with fn applied to the events it is given until it returns true
// once; the test fails when it never does.
inline std::string tampered(const harness::ScratchDir& dir, const std::string& from,
                            const std::function<bool(runtime::LogEvent&)>& fn, const std::string& name = "tampered.lcm") {
  const std::string out = (dir / name).string();
  runtime::LogReader r(from);
  runtime::LogWriter w(out);
  runtime::LogEvent e;
  bool done = false;
  while (r.next(e)) {
    if (!done) done = fn(e);
    REQUIRE(w.write(e.utime, e.channel, e.data.data(), e.data.size()));
  }
  REQUIRE(done);
  return out;
}

}  // namespace bricklayer::test
