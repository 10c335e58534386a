#include "bricklayer/logger/part_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace bricklayer::logger {

PartFile::PartFile(std::string path) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot create the log file " + path_ + ": " + std::strerror(errno));
}

PartFile::~PartFile() { close(); }

size_t PartFile::append(const std::vector<uint8_t>& bytes, const std::vector<size_t>& ends) {
  if (fd_ < 0 || bytes.empty()) return 0;
  size_t done = 0;
  int err = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      err = n < 0 ? errno : ENOSPC;  // write(2) returning 0 for a regular file: no room
      break;
    }
  }
  // Events wholly written.
  size_t complete = 0;
  while (complete < ends.size() && ends[complete] <= done) ++complete;
  const size_t kept_bytes = complete ? ends[complete - 1] : 0;
  if (done > kept_bytes) {
    // A torn event at the end: cut it off, so what the file holds is exactly the events counted.
    if (::ftruncate(fd_, static_cast<off_t>(size_ + static_cast<int64_t>(kept_bytes))) != 0 ||
        ::lseek(fd_, static_cast<off_t>(size_ + static_cast<int64_t>(kept_bytes)), SEEK_SET) < 0)
      error_ = "cannot cut a torn event off " + path_ + ": " + std::strerror(errno);
  }
  size_ += static_cast<int64_t>(kept_bytes);
  events_ += static_cast<int64_t>(complete);
  if (err != 0) {
    disk_full_ = err == ENOSPC || err == EDQUOT;
    if (error_.empty()) error_ = "writing " + path_ + ": " + std::strerror(err);
  }
  return complete;
}

bool PartFile::close() {
  if (fd_ < 0) return true;
  const bool synced = ::fsync(fd_) == 0;
  ::close(fd_);
  fd_ = -1;
  return synced;
}

}  // namespace bricklayer::logger
