// Standard LCM log files (the format of lcm-logger, lcm-logplayer and lcm::LogFile), read and written
// without trusting the bytes. Each event: sync word 0xEDA1DA01, event number (int64), utime (int64),
// channel length (int32), data length (int32), channel, data; big-endian.
//
// Why our own reader: lcm::LogFile stops at the first torn event and cannot tell a clean end from a
// truncated file, so a log written onto a full disk looked complete and "0 mismatches" hid everything
// after the tear. LogReader checks that every event is followed by the next sync word (or the end of
// the file), skips a damaged region by searching for the next intact event, and reports each region
// it skipped (damage()), so tools can say exactly what was lost and still read what follows.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace bricklayer::runtime {

inline constexpr uint32_t kLogSyncWord = 0xEDA1DA01;
inline constexpr int64_t kLogEventHeaderBytes = 28;
inline constexpr int64_t kMaxLogChannelBytes = 255;

struct LogEvent {
  int64_t number = 0;   // as recorded (lcm-logger counts from 0)
  int64_t utime = 0;    // the recorder's receive time, microseconds since the epoch
  std::string channel;
  std::vector<uint8_t> data;
  int64_t offset = 0;   // where the event starts in the file
};

// A region of a log that held no intact event.
struct LogDamage {
  int64_t offset = 0;   // first byte skipped
  int64_t bytes = 0;    // how many were skipped
  bool at_end = false;  // the file ends inside this region (a truncated last event)
  std::string describe() const;
};

class LogReader {
 public:
  // Throws std::runtime_error naming the path when it cannot be opened.
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  // The next intact event; false at the end of the file. Damaged regions are skipped and recorded.
  bool next(LogEvent& event);

  // Continues reading at offset (the start of an event, e.g. from a recording's index).
  void seek(int64_t offset);

  const std::vector<LogDamage>& damage() const { return damage_; }
  int64_t position() const { return position_; }
  int64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  struct Header {
    int64_t number = 0, utime = 0;
    int32_t channel_bytes = 0, data_bytes = 0;
  };
  bool read_at(int64_t offset, void* out, size_t bytes);
  bool plausible_header_at(int64_t offset, Header& header);
  bool intact_event_at(int64_t offset, Header& header, bool strict);
  // The offset of the first intact event starting in [from, to), or -1.
  int64_t find_event_in(int64_t from, int64_t to, bool strict);

  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t size_ = 0;
  int64_t position_ = 0;
  std::vector<LogDamage> damage_;
};

// Writes an LCM log file event by event, checking every write. Numbers events from 0.
class LogWriter {
 public:
  // Creates or truncates path; throws std::runtime_error naming it when it cannot.
  explicit LogWriter(const std::string& path);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  // False when the file refused the event (it may then hold part of it: start a new file).
  bool write(int64_t utime, const std::string& channel, const uint8_t* data, size_t size);
  // Flushes to the operating system; false on error.
  bool flush();
  int64_t events() const { return events_; }
  int64_t bytes() const { return bytes_; }

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
  int64_t events_ = 0;
  int64_t bytes_ = 0;
};

// The encoded bytes of one event (for writers that manage their own files).
std::vector<uint8_t> encode_log_event(int64_t number, int64_t utime, const std::string& channel, const uint8_t* data,
                                      size_t size);

}  // namespace bricklayer::runtime
