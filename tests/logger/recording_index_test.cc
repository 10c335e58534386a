// The recording index: written as JSON lines, read back (a torn last line skipped), seeking by time.
#include <catch2/catch.hpp>

#include <fstream>

#include "bricklayer/logger/recording_index.h"
#include "harness/scratch.h"

using namespace bricklayer;

TEST_CASE("the index finds the part and offset for a time, the moments and the losses") {
  harness::ScratchDir dir("index");
  const std::string path = (dir / "day.index").string();
  {
    logger::IndexWriter w(path);
    w.part((dir / "day.00").string(), 1'000'000);
    w.seek((dir / "day.00").string(), 2'000'000, 5000);
    w.moment({2'500'000, "red", "frame 7"});
    w.part((dir / "day.01").string(), 3'000'000);
    w.seek((dir / "day.01").string(), 4'000'000, 900);
    w.loss({12, 4'100'000, 4'200'000, "disk full"});
    CHECK(w.failed_lines() == 0);
  }
  {
    std::ofstream torn(path, std::ios::app);
    torn << R"({"seek":5000000,"part":"day.01","off)";  // a crash in the middle of a line
  }
  const auto index = logger::RecordingIndex::load(path);
  CHECK(index.unreadable_lines() == 1);
  REQUIRE(index.parts().size() == 2);
  CHECK(index.parts()[1] == (dir / "day.01").string());
  auto at = [&](int64_t t) { return *index.seek(t); };
  CHECK(at(0).part == (dir / "day.00").string());  // before the recording: its start
  CHECK(at(0).offset == 0);
  CHECK(at(2'400'000).offset == 5000);
  CHECK(at(3'500'000).part == (dir / "day.01").string());
  CHECK(at(3'500'000).offset == 0);
  CHECK(at(9'000'000).offset == 900);
  REQUIRE(index.moments().size() == 1);
  CHECK(index.moments()[0].kind == "red");
  CHECK(index.moments()[0].note == "frame 7");
  REQUIRE(index.losses().size() == 1);
  CHECK(index.losses()[0].events == 12);
  CHECK(logger::RecordingIndex::path_for("logs/demo-1.03") == "logs/demo-1.index");
  CHECK(logger::RecordingIndex::path_for("logs/demo.lcm").empty());
  CHECK_THROWS_AS(logger::RecordingIndex::load((dir / "none.index").string()), std::runtime_error);
}
