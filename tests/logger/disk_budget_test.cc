// DiskBudget: the series within its bytes, the oldest recordings deleted first, parts in order, an
// index with its recording's last part, never a file being written, never another series' files.
#include <catch2/catch.hpp>

#include <sys/mount.h>
#include <sys/stat.h>
#include <utime.h>

#include <filesystem>

#include "bricklayer/logger/disk_budget.h"
#include "harness/scratch.h"

using namespace bricklayer;
namespace fs = std::filesystem;

namespace {
// A file of `kb` KB last written `age_s` seconds before a fixed moment.
void file(const fs::path& p, int kb, int age_s) {
  harness::write_file(p, std::string(static_cast<size_t>(kb) * 1024, 'x'));
  const struct utimbuf t{1'800'000'000 - age_s, 1'800'000'000 - age_s};
  REQUIRE(::utime(p.c_str(), &t) == 0);
}
}  // namespace

TEST_CASE("the budget deletes the oldest recording first, its parts in order, its index last") {
  harness::ScratchDir dir("budget");
  file(dir / "demo-1.00", 100, 300);
  file(dir / "demo-1.01", 100, 250);
  file(dir / "demo-1.index", 1, 250);
  file(dir / "demo-2.00", 100, 200);
  file(dir / "demo-2.01", 100, 100);
  file(dir / "demo-2.index", 1, 100);
  file(dir / "other-1.00", 500, 1000);  // another series: never touched
  file(dir / "demo-notes.txt", 50, 1000);  // not a log: never touched

  logger::DiskBudget budget({dir.str(), "demo-", 450 * 1024, 0});
  CHECK(budget.used_bytes() == 402 * 1024);
  const auto files = budget.scan();
  REQUIRE(files.size() == 6);
  CHECK(fs::path(files[0].path).filename() == "demo-1.00");
  CHECK(fs::path(files[2].path).filename() == "demo-1.index");
  CHECK(fs::path(files[5].path).filename() == "demo-2.index");

  CHECK(budget.make_room(40 * 1024, {}));  // fits: nothing deleted
  CHECK(budget.deleted_files() == 0);
  CHECK(budget.make_room(100 * 1024, {}));  // 402 + 100 > 450: the oldest part goes
  CHECK_FALSE(fs::exists(dir / "demo-1.00"));
  CHECK(fs::exists(dir / "demo-1.01"));
  CHECK(fs::exists(dir / "demo-1.index"));
  CHECK(budget.deleted_files() == 1);
  CHECK(budget.make_room(200 * 1024, {}));  // the rest of recording 1, its index with its last part
  CHECK_FALSE(fs::exists(dir / "demo-1.01"));
  CHECK_FALSE(fs::exists(dir / "demo-1.index"));
  CHECK(fs::exists(dir / "demo-2.00"));
  CHECK(budget.deleted_files() == 3);
  // The files being written are never deleted: what cannot be made room for is refused.
  CHECK_FALSE(budget.make_room(400 * 1024, {(dir / "demo-2.00").string(), (dir / "demo-2.01").string(),
                                             (dir / "demo-2.index").string()}));
  CHECK(fs::exists(dir / "demo-2.00"));
  CHECK(fs::exists(dir / "other-1.00"));
  CHECK(fs::exists(dir / "demo-notes.txt"));
  CHECK(budget.used_bytes() == 201 * 1024);
}

TEST_CASE("the minimum free space is kept on a real small file system") {
  harness::ScratchDir dir("budget-free");
  const fs::path mnt = dir / "mnt";
  fs::create_directories(mnt);
  REQUIRE(::mount("bricklayer-budget-test", mnt.c_str(), "tmpfs", 0, "size=1m") == 0);
  for (int i = 0; i < 8; ++i) file(mnt / ("r.0" + std::to_string(i)), 100, 100 - i);
  logger::DiskBudget budget({mnt.string(), "r.", 0, 400 * 1024});
  const int64_t free_before = budget.free_bytes();
  CHECK(free_before < 300 * 1024);
  CHECK(budget.make_room(100 * 1024, {(mnt / "r.07").string()}));
  CHECK(budget.free_bytes() - 100 * 1024 >= 400 * 1024);
  // The oldest went first.
  CHECK_FALSE(fs::exists(mnt / "r.00"));
  CHECK(fs::exists(mnt / "r.07"));
  CHECK(fs::exists(mnt / "r.06"));
  // More than the file system can ever give: refused, the kept file stays.
  CHECK_FALSE(budget.make_room(2 << 20, {(mnt / "r.07").string()}));
  CHECK(fs::exists(mnt / "r.07"));
  ::umount(mnt.c_str());
}
