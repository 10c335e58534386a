// The disk check of the real bricklayer-doctor against a real, small file system: a 4 MB tmpfs
// mounted in a mount namespace of the doctor's own (unshare -m), so nothing outside the test sees it.
#include <catch2/catch.hpp>

#include <filesystem>

#include "bricklayer/doctor/disk_check.h"
#include "doctor_test_util.h"

using namespace bricklayer;
using test::check_line;
using test::severity;
namespace fs = std::filesystem;

namespace {

// The doctor with `dir` a fresh 4 MiB tmpfs holding `preload` bytes of old logs in logs/.
test::DoctorRun doctor_on_tmpfs(const fs::path& dir, const std::string& logger, const std::string& min_free_mb, int preload_kb = 0) {
  const std::string profile = test::write_file(
      dir.parent_path() / (dir.filename().string() + ".json"),
      R"({"logger":)" + logger + R"(,"modules":[{"name":"prediction","command":["bricklayer-prediction"]}]})");
  std::string script = "mount -t tmpfs -o size=4m bricklayer-doctor-test " + dir.string() + " && mkdir -p " + dir.string() + "/logs";
  if (preload_kb > 0)
    script += " && head -c " + std::to_string(preload_kb * 1024) + " /dev/zero > " + dir.string() + "/logs/old.00";
  script += " && exec \"$0\" \"$@\"";
  std::vector<std::string> argv = {"/usr/bin/unshare", getuid() == 0 ? "-m" : "-rm", "sh", "-c", script,
                                   harness::program_path("bricklayer-doctor"), profile, "--root", dir.string(), "--checks", "disk",
                                   "--min-free-mb", min_free_mb};
  return test::run_capture(argv);
}

}  // namespace

TEST_CASE("a 4 MB disk: a 2 MB log series fits, a 10 MB one warns, a larger minimum free fails") {
  const fs::path dir = test::temp_dir("disk") / "mnt";
  fs::create_directories(dir);
  auto r = doctor_on_tmpfs(dir, R"({"file":"logs/t","rotate":2,"split_mb":1})", "1");
  INFO(r.out);
  REQUIRE(r.out.find("mount:") == std::string::npos);
  std::string line = check_line(r.out, "disk");
  CHECK(line.find("ok       disk                 " + (dir / "logs").string() + ": 4.0 MB free, logs use 0.0 MB; the series fits") == 0);
  CHECK(r.code == 0);

  r = doctor_on_tmpfs(dir, R"({"file":"logs/t","rotate":10,"split_mb":1})", "1");
  INFO(r.out);
  line = check_line(r.out, "disk");
  CHECK(severity(line) == "warning");
  CHECK(line.find("may grow to 10.0 MB (rotate 10 x split_mb 1)") != std::string::npos);
  CHECK(r.code == 0);

  r = doctor_on_tmpfs(dir, R"({"file":"logs/t","rotate":2,"split_mb":1})", "8");
  INFO(r.out);
  line = check_line(r.out, "disk");
  CHECK(severity(line) == "FAILED");
  CHECK(line.find("below the 8.0 MB that must stay free") != std::string::npos);
  CHECK(r.code == 1);
  fs::remove_all(dir.parent_path());
}

TEST_CASE("the logger's disk budget and minimum free space are what the doctor checks") {
  const fs::path dir = test::temp_dir("disk-budget") / "mnt";
  fs::create_directories(dir);
  auto r = doctor_on_tmpfs(dir, R"({"file":"logs/t-%Y","split_mb":1,"budget_mb":3,"min_free_mb":0.5})", "0");
  INFO(r.out);
  std::string line = check_line(r.out, "disk");
  CHECK(severity(line) == "ok");
  CHECK(line.find("the series fits (3.0 MB, budget_mb 3 of the series t-*)") != std::string::npos);
  // The logger keeps 2 MB free: with its 3 MB budget that is more than the 4 MB disk holds.
  r = doctor_on_tmpfs(dir, R"({"file":"logs/t-%Y","split_mb":1,"budget_mb":3,"min_free_mb":2})", "0");
  INFO(r.out);
  line = check_line(r.out, "disk");
  CHECK(severity(line) == "warning");
  CHECK(line.find("more than fits above the 2.0 MB to keep free") != std::string::npos);
  fs::remove_all(dir.parent_path());
}

TEST_CASE("logs already on the disk count as reusable by the rotation, rotate 0 never deletes and warns") {
  const fs::path dir = test::temp_dir("disk-used") / "mnt";
  fs::create_directories(dir);
  // 3 MB of old logs leave 1 MB free: still fits a 3 MB series that will delete them.
  auto r = doctor_on_tmpfs(dir, R"({"file":"logs/t","rotate":3,"split_mb":1})", "0.5", 3072);
  INFO(r.out);
  std::string line = check_line(r.out, "disk");
  CHECK(line.find("1.0 MB free, logs use 3.0 MB") != std::string::npos);
  CHECK(severity(line) == "ok");
  r = doctor_on_tmpfs(dir, R"({"file":"logs/t","rotate":0,"split_mb":1})", "0.5");
  INFO(r.out);
  line = check_line(r.out, "disk");
  CHECK(severity(line) == "warning");
  CHECK(line.find("rotate 0 (old files are never deleted): at about 3.2 GB per hour the disk is full in 0.0 h") != std::string::npos);
  fs::remove_all(dir.parent_path());
}

TEST_CASE("the budget from the profile, and a folder that does not exist yet") {
  doctor::HostPlan plan;
  plan.root = "/exhibit";
  CHECK(doctor::budget_from_plan(plan, 0).folder.empty());
  CHECK(doctor::check_disk(doctor::budget_from_plan(plan, 0)).severity == doctor::Severity::kOk);  // no logger here
  plan.logger = launcher::LoggerSpec{"logs/x-%Y", 20, 200};
  auto b = doctor::budget_from_plan(plan, 5);
  CHECK(b.folder == "/exhibit/logs");
  CHECK(b.max_bytes == 20ull * 200 * 1048576);
  CHECK(b.min_free_bytes == 5);
  // The logger's budget and minimum free space, as the logger enforces them.
  plan.logger->budget_mb = 5000;
  plan.logger->min_free_mb = 1000;
  b = doctor::budget_from_plan(plan, 5);
  CHECK(b.max_bytes == 5000ull * 1048576);
  CHECK(b.min_free_bytes == 1000ull * 1048576);
  CHECK(b.source == "budget_mb 5000 of the series x-*");
  // Not created yet: measured at the nearest existing parent.
  b.folder = (fs::temp_directory_path() / "bricklayer-doctor-none" / "logs").string();
  b.max_bytes = 1;
  CHECK(doctor::check_disk(b).severity == doctor::Severity::kOk);
}
