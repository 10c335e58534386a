#include "harness/demo_profile.h"

#include <nlohmann/json.hpp>

namespace bricklayer::harness {

DemoProfile scratch_demo_profile(const ScratchDir& dir) {
  nlohmann::json profile = nlohmann::json::parse(read_file(source_dir() / "launch/profiles/demo.json"));
  profile["logger"]["file"] = (dir / "demo").string();
  DemoProfile out;
  for (auto& m : profile["modules"])
    for (auto& arg : m["command"]) {
      if (arg == "logs/snapshots") arg = (dir / "snapshots").string();
      if (arg == "logs/rounds.json") {
        arg = (dir / "rounds.json").string();
        out.has_round_book = true;
      }
    }
  out.file = dir / "demo.json";
  write_file(out.file, profile.dump(1));
  return out;
}

}  // namespace bricklayer::harness
