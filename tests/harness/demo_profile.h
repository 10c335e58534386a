// The shipped demo profile for a test that launches it: what it would write under logs/ goes into a
// scratch folder instead.
#pragma once

#include <filesystem>

#include "harness/scratch.h"

namespace bricklayer::harness {

struct DemoProfile {
  std::filesystem::path file;   // dir/demo.json, the profile to pass to bricklayer-launch
  bool has_round_book = false;  // whether the shipped profile keeps a round book (now dir/rounds.json)
};

// launch/profiles/demo.json with its log (dir/demo.*), snapshots (dir/snapshots) and round book
// (dir/rounds.json) moved into dir, written as dir/demo.json.
DemoProfile scratch_demo_profile(const ScratchDir& dir);

}  // namespace bricklayer::harness
