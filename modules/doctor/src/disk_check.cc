#include "bricklayer/doctor/disk_check.h"

#include <sys/statvfs.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace bricklayer::doctor {
namespace {
namespace fs = std::filesystem;

std::string size_text(uint64_t bytes) {
  char text[32];
  if (bytes >= (1ull << 30))
    std::snprintf(text, sizeof(text), "%.1f GB", bytes / 1073741824.0);
  else
    std::snprintf(text, sizeof(text), "%.1f MB", bytes / 1048576.0);
  return text;
}

// The demo's log grows 3.16 GB per hour with camera frames (NOTES: simcam JPEG 640x480 at 30 fps).
constexpr double kBytesPerHour = 3.16e9;

}  // namespace

DiskBudget budget_from_plan(const HostPlan& plan, uint64_t min_free_bytes) {
  DiskBudget b;
  b.min_free_bytes = min_free_bytes;
  if (!plan.logger) return b;
  fs::path file = fs::path(plan.logger->file);
  if (!file.is_absolute()) file = fs::path(plan.root) / file;
  b.folder = file.parent_path().lexically_normal().string();
  const launcher::LoggerSpec& l = *plan.logger;
  // The logger's own minimum, when the profile sets one, is what it keeps free: the doctor asks for it too.
  b.min_free_bytes = std::max(min_free_bytes, static_cast<uint64_t>(l.min_free_mb * 1048576));
  if (l.budget_mb > 0) {
    b.max_bytes = static_cast<uint64_t>(l.budget_mb * 1048576);  // the logger's MB are MiB
    b.source = "budget_mb " + std::to_string(static_cast<int64_t>(l.budget_mb)) + " of the series " +
               launcher::series_prefix(l.file) + "*";
  } else if (l.rotate > 0) {
    b.max_bytes = static_cast<uint64_t>(l.rotate * l.split_mb * 1048576);
    b.source = "rotate " + std::to_string(l.rotate) + " x split_mb " + std::to_string(static_cast<int>(l.split_mb));
  } else {
    b.source = "rotate 0 (old files are never deleted)";
  }
  return b;
}

CheckResult check_disk(const DiskBudget& b) {
  const std::string name = "disk";
  if (b.folder.empty()) return CheckResult::ok(name, "the profile records no log on this host");
  // The folder may not exist yet (the launcher creates it): measure the nearest existing parent.
  fs::path where = b.folder;
  std::error_code ec;
  while (!where.empty() && !fs::exists(where, ec)) where = where.parent_path();
  struct statvfs st{};
  if (where.empty() || statvfs(where.c_str(), &st) != 0)
    return CheckResult::failed(name, "cannot measure the free space at " + b.folder, "create the folder: mkdir -p " + b.folder);
  const uint64_t free_bytes = static_cast<uint64_t>(st.f_bavail) * st.f_frsize;
  uint64_t used = 0;
  if (fs::is_directory(b.folder, ec))
    for (const auto& e : fs::recursive_directory_iterator(b.folder, fs::directory_options::skip_permission_denied, ec))
      if (e.is_regular_file(ec)) used += e.file_size(ec);
  const std::string found = b.folder + ": " + size_text(free_bytes) + " free, logs use " + size_text(used);
  const std::string clean = "delete old logs in " + b.folder + " or give the logger a larger disk";
  if (free_bytes < b.min_free_bytes)
    return CheckResult::failed(name, found + ", below the " + size_text(b.min_free_bytes) + " that must stay free", clean);
  const uint64_t spare = free_bytes - b.min_free_bytes;
  if (!b.max_bytes) {
    char hours[32];
    std::snprintf(hours, sizeof(hours), "%.1f", spare / kBytesPerHour);
    return CheckResult::warning(name, found + "; " + b.source + ": at about 3.2 GB per hour the disk is full in " + hours + " h",
                                "give the profile's logger a rotate > 0");
  }
  // Logs already in the folder may belong to the series and be deleted by its rotation: count them as
  // reusable, so a full series does not read as a shortage.
  const uint64_t room = spare + used;
  if (room < *b.max_bytes)
    return CheckResult::warning(name, found + "; the log series may grow to " + size_text(*b.max_bytes) + " (" + b.source +
                                          "), more than fits above the " + size_text(b.min_free_bytes) + " to keep free",
                                clean + ", or lower rotate / split_mb");
  return CheckResult::ok(name, found + "; the series fits (" + size_text(*b.max_bytes) + ", " + b.source + ")");
}

}  // namespace bricklayer::doctor
