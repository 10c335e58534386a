// One file of a recording, written with checked writes so the logger's count of what is on the disk is
// exact. Events are appended in batches with write(2) (no stdio buffer that could fail later, at a
// flush, after the events were counted); a short or failed write is cut back to the end of the last
// complete event (ftruncate), so the file stays a clean standard LCM log up to the loss, and the
// caller starts a new file rather than appending behind a torn event.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace bricklayer::logger {

class PartFile {
 public:
  // Creates path (it must not exist: an existing file is never overwritten). Throws std::runtime_error
  // naming the path and the reason.
  explicit PartFile(std::string path);
  ~PartFile();  // close() without throwing
  PartFile(const PartFile&) = delete;
  PartFile& operator=(const PartFile&) = delete;

  // Appends bytes, which hold whole events ending at the offsets in ends (ascending, the last one
  // bytes.size()). Returns how many of those events are now complete in the file. On a write error
  // the incomplete tail is cut off again; failed() and error() say why.
  size_t append(const std::vector<uint8_t>& bytes, const std::vector<size_t>& ends);

  // fsync and close; idempotent. False when the sync failed (the data may not be on the disk).
  bool close();

  const std::string& path() const { return path_; }
  int64_t size() const { return size_; }
  int64_t events() const { return events_; }
  bool failed() const { return !error_.empty(); }
  const std::string& error() const { return error_; }
  // Whether the last failure was the disk being full (ENOSPC, EDQUOT), as opposed to an I/O error.
  bool disk_full() const { return disk_full_; }

 private:
  std::string path_;
  int fd_ = -1;
  int64_t size_ = 0;
  int64_t events_ = 0;
  std::string error_;
  bool disk_full_ = false;
};

}  // namespace bricklayer::logger
