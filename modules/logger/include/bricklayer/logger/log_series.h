// Which file the logger writes next: the naming and rotation rules of Debian's lcm-logger 1.3.1, so
// the launcher's profile format ("file", "rotate", "split_mb") and every tool that finds logs by name
// keep working.
//   rotate N > 0: always write BASE.0; before a new file, BASE.k is renamed to BASE.k+1 and BASE.<N-1>
//                 deleted, so at most N files (the newest is BASE.0).
//   rotate 0:     increment: BASE.00, BASE.01, ... numbered after the highest one already there and
//                 never reusing a number (so the numbers keep the time order when the disk budget
//                 deletes the oldest parts); nothing is ever renamed here.
#pragma once

#include <string>

namespace bricklayer::logger {

class LogSeries {
 public:
  // base: the file name without suffix. Throws std::invalid_argument on an empty base or rotate < 0.
  LogSeries(std::string base, int rotate);

  // Makes room (rotation) and returns the path of the next file to write. Creates missing parent
  // directories. Throws std::runtime_error (saying which path and why) when a rename, delete or
  // mkdir fails. Call only once the previous file is closed.
  std::string next();

  const std::string& base() const { return base_; }
  int rotate() const { return rotate_; }

 private:
  std::string base_;
  int rotate_;
  int next_ = -1;  // increment: the next number to try (-1: not scanned yet)
};

// The base name with strftime conversions expanded for the local time t (seconds since the epoch).
// Throws std::invalid_argument when the expansion is empty or too long.
std::string expand_strftime(const std::string& pattern, long long t);

}  // namespace bricklayer::logger
