// PartFile: checked writes, and a torn event cut off on a full disk (a real 64 KB tmpfs in a mount
// namespace of the test's own: see tests/logger/CMakeLists.txt).
#include <catch2/catch.hpp>

#include <sys/mount.h>

#include <filesystem>

#include "bricklayer/logger/part_file.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/scratch.h"

using namespace bricklayer;
namespace fs = std::filesystem;

namespace {
// n events of `size` data bytes each on channel "C", encoded, with their end offsets.
void events(int n, size_t size, std::vector<uint8_t>& bytes, std::vector<size_t>& ends, int first = 0) {
  for (int i = 0; i < n; ++i) {
    std::vector<uint8_t> data(size, static_cast<uint8_t>(first + i));
    const auto e = runtime::encode_log_event(first + i, 1000 + first + i, "C", data.data(), data.size());
    bytes.insert(bytes.end(), e.begin(), e.end());
    ends.push_back(bytes.size());
  }
}
int read_back(const std::string& path, bool& damaged) {
  runtime::LogReader r(path);
  runtime::LogEvent e;
  int n = 0;
  while (r.next(e)) ++n;
  damaged = !r.damage().empty();
  return n;
}
}  // namespace

TEST_CASE("a part file holds exactly the events it counts, and never overwrites a file") {
  harness::ScratchDir dir("part-file");
  const std::string path = (dir / "p.00").string();
  logger::PartFile f(path);
  std::vector<uint8_t> bytes;
  std::vector<size_t> ends;
  events(5, 100, bytes, ends);
  CHECK(f.append(bytes, ends) == 5);
  CHECK(f.size() == static_cast<int64_t>(bytes.size()));
  CHECK(f.close());
  bool damaged = true;
  CHECK(read_back(path, damaged) == 5);
  CHECK_FALSE(damaged);
  CHECK_THROWS_WITH(logger::PartFile(path), Catch::Contains("cannot create the log file " + path));
}

TEST_CASE("on a full disk the torn event is cut off: the file reads back clean up to the loss") {
  harness::ScratchDir dir("part-file-full");
  const fs::path mnt = dir / "mnt";
  fs::create_directories(mnt);
  // Our own mount namespace (the test runs under unshare -m): nobody else sees this file system.
  REQUIRE(::mount("bricklayer-part-test", mnt.c_str(), "tmpfs", 0, "size=64k") == 0);
  {
    const std::string path = (mnt / "p.00").string();
    logger::PartFile f(path);
    std::vector<uint8_t> bytes;
    std::vector<size_t> ends;
    events(100, 1000, bytes, ends);  // ~100 KB into 64 KB
    const size_t kept = f.append(bytes, ends);
    CHECK(kept > 10);
    CHECK(kept < 100);
    CHECK(f.failed());
    CHECK(f.disk_full());
    CHECK(f.error().find("No space left") != std::string::npos);
    CHECK(f.size() == static_cast<int64_t>(ends[kept - 1]));
    CHECK(static_cast<int64_t>(fs::file_size(path)) == f.size());
    f.close();
    bool damaged = true;
    CHECK(read_back(path, damaged) == static_cast<int>(kept));
    CHECK_FALSE(damaged);
  }
  ::umount(mnt.c_str());
}
