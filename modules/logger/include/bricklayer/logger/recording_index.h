// A recording's index (NAME.index beside the parts NAME.00, NAME.01, ...), so tools seek by wall time
// and find the moments that matter without reading a day of frames. JSON lines, appended as the logger
// writes (a torn last line, from a crash, is skipped when read):
//   {"part":"NAME.00","t":U}                            a part starts; its first event has utime U
//   {"seek":U,"part":"NAME.00","offset":N}              the event at byte N of the part has utime U
//                                                       (one about every second of the recording)
//   {"moment":"red","t":U,"note":"frame 77, score 131"}  red appears, collapse, round_start, round_end,
//                                                       mark (the operator's), with the logger's time
//   {"loss":N,"from":U1,"to":U2,"reason":"disk full"}   N events received but not kept
// Times are the logger's receive times (the events' utime in the parts), microseconds since the epoch.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bricklayer::logger {

struct SeekPoint {
  int64_t utime = 0;
  std::string part;    // path of the part (the index's folder + the recorded file name)
  int64_t offset = 0;  // byte offset of an event in it
};

struct Moment {
  int64_t utime = 0;
  std::string kind;  // red, collapse, round_start, round_end, mark
  std::string note;
};

struct Loss {
  int64_t events = 0;
  int64_t from_utime = 0, to_utime = 0;
  std::string reason;
};

// Appends index lines; every write is checked (a failed line is counted, never half-kept: a torn line
// is cut off like a torn event).
class IndexWriter {
 public:
  // Opens (appending: a restarted logger continues its recording's index). Throws std::runtime_error.
  explicit IndexWriter(std::string path);
  ~IndexWriter();
  IndexWriter(const IndexWriter&) = delete;
  IndexWriter& operator=(const IndexWriter&) = delete;

  void part(const std::string& part_path, int64_t first_utime);
  void seek(const std::string& part_path, int64_t utime, int64_t offset);
  void moment(const Moment& m);
  void loss(const Loss& l);

  const std::string& path() const { return path_; }
  int64_t failed_lines() const { return failed_; }
  int64_t bytes() const { return bytes_; }

 private:
  void line(const std::string& json);
  std::string path_;
  int fd_ = -1;
  int64_t failed_ = 0;
  int64_t bytes_ = 0;
};

class RecordingIndex {
 public:
  // Reads path (NAME.index). Throws std::runtime_error when it cannot be read.
  static RecordingIndex load(const std::string& path);
  // The index of the recording a part belongs to ("logs/demo-X.03" -> "logs/demo-X.index"), "" when
  // the file name has no numeric suffix.
  static std::string path_for(const std::string& part_path);

  // The last seek point at or before utime (the first one when utime is earlier); nullopt when none.
  std::optional<SeekPoint> seek(int64_t utime) const;
  // Parts in recording order, as the index names them (some may have been deleted since).
  std::vector<std::string> parts() const;

  const std::vector<SeekPoint>& seek_points() const { return seeks_; }
  const std::vector<Moment>& moments() const { return moments_; }
  const std::vector<Loss>& losses() const { return losses_; }
  int64_t unreadable_lines() const { return unreadable_; }

 private:
  std::vector<SeekPoint> seeks_;  // ascending utime
  std::vector<std::string> parts_;
  std::vector<Moment> moments_;
  std::vector<Loss> losses_;
  int64_t unreadable_ = 0;
};

}  // namespace bricklayer::logger
