// The disk a day of recordings may use: at most max_bytes for every recording of the series, and at
// least min_free_bytes left free on the file system. Room is made by deleting the oldest recordings'
// files first (and, within a recording, its oldest parts first), never the files being written, so
// the disk never fills and what is kept is always the newest data.
//
// A series is the recordings in one folder whose file names start with one prefix (the launcher passes
// the profile pattern's fixed part, "demo-" for logs/demo-%Y%m%d-%H%M%S): the parts NAME.00, NAME.01,
// ... (or NAME.0 .. NAME.<N-1> when rotating) and the index NAME.index of each recording NAME.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace bricklayer::logger {

struct BudgetOptions {
  std::string folder;          // where the series lives
  std::string prefix;          // file names of the series start with this
  int64_t max_bytes = 0;       // every file of the series together; 0 = no limit
  int64_t min_free_bytes = 0;  // free space to leave on the file system; 0 = none
};

struct SeriesFile {
  std::string path;
  std::string recording;  // the path without its last suffix
  int64_t bytes = 0;
  int64_t mtime_ns = 0;
  int part = -1;          // the numeric suffix; -1 for the index
};

class DiskBudget {
 public:
  explicit DiskBudget(BudgetOptions options);

  // Deletes the oldest files of the series until `need` more bytes fit under max_bytes and leave
  // min_free_bytes free, never a path in keep. True when they fit.
  bool make_room(int64_t need, const std::set<std::string>& keep);
  // Bytes just written into a file of the series (accounted until the next scan).
  void wrote(int64_t bytes);

  int64_t used_bytes() const { return used_; }         // the series, as of the last scan plus writes
  int64_t free_bytes() const;                          // on the file system now (-1 when unknown)
  int64_t deleted_files() const { return deleted_files_; }
  int64_t deleted_bytes() const { return deleted_bytes_; }
  const BudgetOptions& options() const { return options_; }
  bool limited() const { return options_.max_bytes > 0 || options_.min_free_bytes > 0; }

  // The series' files, oldest recording first, each recording's parts in order, its index last.
  std::vector<SeriesFile> scan() const;

 private:
  void rescan();

  BudgetOptions options_;
  int64_t used_ = 0;
  int64_t writes_since_scan_ = 0;
  int64_t deleted_files_ = 0;
  int64_t deleted_bytes_ = 0;
};

}  // namespace bricklayer::logger
