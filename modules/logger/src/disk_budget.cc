#include "bricklayer/logger/disk_budget.h"

#include <sys/stat.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <system_error>
#include <tuple>

#include "bricklayer/common/log.h"

namespace bricklayer::logger {
namespace fs = std::filesystem;
namespace {

// Rescanning the folder costs a listing and a stat per file: often enough to notice files that
// appear or vanish behind the logger's back, rarely enough to cost nothing.
constexpr int64_t kRescanAfterBytes = 8 << 20;

// "NAME.00" -> 0, "NAME.index" -> -1, anything else -> -2.
int suffix_kind(const std::string& name, std::string& recording) {
  const auto dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == name.size()) return -2;
  const std::string suffix = name.substr(dot + 1);
  recording = name.substr(0, dot);
  if (suffix == "index") return -1;
  if (suffix.size() > 9 || !std::all_of(suffix.begin(), suffix.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return -2;
  return std::stoi(suffix);
}

}  // namespace

DiskBudget::DiskBudget(BudgetOptions options) : options_(std::move(options)) {
  if (options_.folder.empty()) options_.folder = ".";
  rescan();
}

std::vector<SeriesFile> DiskBudget::scan() const {
  std::vector<SeriesFile> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(options_.folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.compare(0, options_.prefix.size(), options_.prefix) != 0) continue;
    std::string recording;
    const int part = suffix_kind(name, recording);
    if (part == -2) continue;
    struct stat st{};
    if (::stat(entry.path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    SeriesFile f;
    f.path = entry.path().string();
    f.recording = (fs::path(options_.folder) / recording).string();
    f.bytes = static_cast<int64_t>(st.st_size);
    f.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
    f.part = part;
    files.push_back(std::move(f));
  }
  // A recording's age is its oldest part's last write.
  std::map<std::string, int64_t> age;
  for (const auto& f : files) {
    if (f.part < 0) continue;
    auto [it, fresh] = age.emplace(f.recording, f.mtime_ns);
    if (!fresh) it->second = std::min(it->second, f.mtime_ns);
  }
  for (const auto& f : files)
    if (!age.count(f.recording)) age[f.recording] = f.mtime_ns;  // an index without parts
  std::sort(files.begin(), files.end(), [&](const SeriesFile& a, const SeriesFile& b) {
    if (a.recording != b.recording) {
      const int64_t x = age[a.recording], y = age[b.recording];
      return x != y ? x < y : a.recording < b.recording;
    }
    // Parts by last write (rotation numbers the newest part 0, increment the oldest: by last write both
    // namings sort right), the index last.
    return std::make_tuple(a.part < 0, a.mtime_ns, a.part) < std::make_tuple(b.part < 0, b.mtime_ns, b.part);
  });
  return files;
}

void DiskBudget::rescan() {
  used_ = 0;
  for (const auto& f : scan()) used_ += f.bytes;
  writes_since_scan_ = 0;
}

void DiskBudget::wrote(int64_t bytes) {
  used_ += bytes;
  writes_since_scan_ += bytes;
}

int64_t DiskBudget::free_bytes() const {
  struct statvfs st{};
  if (::statvfs(options_.folder.c_str(), &st) != 0) return -1;
  return static_cast<int64_t>(st.f_bavail) * static_cast<int64_t>(st.f_frsize);
}

bool DiskBudget::make_room(int64_t need, const std::set<std::string>& keep) {
  if (!limited()) return true;
  if (writes_since_scan_ >= kRescanAfterBytes) rescan();
  auto fits = [&] {
    if (options_.max_bytes > 0 && used_ + need > options_.max_bytes) return false;
    if (options_.min_free_bytes > 0) {
      const int64_t free = free_bytes();
      if (free >= 0 && free - need < options_.min_free_bytes) return false;
    }
    return true;
  };
  if (fits()) return true;
  rescan();
  if (fits()) return true;
  std::vector<SeriesFile> files = scan();
  std::map<std::string, int> parts_left;
  for (const auto& f : files)
    if (f.part >= 0) ++parts_left[f.recording];
  for (const auto& f : files) {
    if (fits()) return true;
    if (keep.count(f.path)) continue;
    // An index goes with its recording's last part (it is what tools seek with).
    if (f.part < 0 && parts_left[f.recording] > 0) continue;
    std::error_code ec;
    if (!fs::remove(f.path, ec)) {
      log::warn("cannot delete the old log ", f.path, " to make room: ", ec.message());
      continue;
    }
    ++deleted_files_;
    deleted_bytes_ += f.bytes;
    used_ -= f.bytes;
    if (f.part >= 0 && --parts_left[f.recording] == 0) {
      // Its index is now useless: delete it at once.
      const std::string index = f.recording + ".index";
      if (!keep.count(index)) {
        const auto size = fs::file_size(index, ec);
        if (!ec && fs::remove(index, ec)) {
          ++deleted_files_;
          deleted_bytes_ += static_cast<int64_t>(size);
          used_ -= static_cast<int64_t>(size);
        }
      }
    }
  }
  return fits();
}

}  // namespace bricklayer::logger
