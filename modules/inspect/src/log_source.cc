#include "bricklayer/inspect/log_source.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace bricklayer::inspect {

namespace {

constexpr uint32_t kSyncWord = 0xEDA1DA01;
constexpr int32_t kMaxChannelLength = 256;  // LCM allows 63 characters; anything beyond 256 is damage
constexpr size_t kHeaderSize = 4 + 8 + 8 + 4 + 4;

uint64_t big_endian(const uint8_t* p, size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

LogSource::LogSource(std::vector<std::string> files) : files_(std::move(files)) {
  for (const auto& f : files_) {
    struct stat st {};
    if (::stat(f.c_str(), &st) != 0) throw LogOpenError("cannot read log " + f + ": " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw LogOpenError("log " + f + " is not a regular file");
    std::FILE* probe = std::fopen(f.c_str(), "rb");
    if (!probe) throw LogOpenError("cannot open log " + f + ": " + std::strerror(errno));
    std::fclose(probe);
    sizes_.push_back(static_cast<uint64_t>(st.st_size));
    total_bytes_ += static_cast<uint64_t>(st.st_size);
  }
}

LogSource::~LogSource() {
  if (file_) std::fclose(file_);
}

bool LogSource::open_next() {
  if (file_) {
    std::fclose(file_);
    file_ = nullptr;
    done_bytes_ += sizes_[current_];
    position_ = 0;
    ++current_;
  } else if (opened_) {
    return false;
  }
  opened_ = true;
  if (current_ >= files_.size()) return false;
  file_ = std::fopen(files_[current_].c_str(), "rb");
  if (!file_) throw LogOpenError("cannot open log " + files_[current_] + ": " + std::strerror(errno));
  static thread_local char buffer[1 << 20];
  std::setvbuf(file_, buffer, _IOFBF, sizeof buffer);
  return true;
}

bool LogSource::read_exact(void* out, size_t n) {
  size_t got = std::fread(out, 1, n, file_);
  position_ += got;
  return got == n;
}

void LogSource::problem(uint64_t offset, bool truncated, std::string what) {
  problems_.push_back({files_[current_], offset, truncated, std::move(what)});
}

bool LogSource::resync(uint64_t from) {
  // Scans for the next sync word starting at byte `from`; leaves the file positioned on it.
  std::fseek(file_, static_cast<long>(from), SEEK_SET);
  position_ = from;
  uint32_t window = 0;
  uint64_t scanned = 0;
  int c;
  while ((c = std::fgetc(file_)) != EOF) {
    ++position_;
    window = (window << 8) | static_cast<uint32_t>(c);
    if (++scanned >= 4 && window == kSyncWord) {
      position_ -= 4;
      std::fseek(file_, static_cast<long>(position_), SEEK_SET);
      return true;
    }
  }
  return false;
}

bool LogSource::next(LogEvent& event) {
  if (!file_ && !open_next()) return false;
  while (true) {
    uint64_t start = position_;
    uint8_t header[kHeaderSize];
    size_t got = std::fread(header, 1, kHeaderSize, file_);
    position_ += got;
    if (got == 0) {
      if (!open_next()) return false;
      continue;
    }
    std::string damage;
    if (got < 4 || big_endian(header, 4) != kSyncWord) {
      damage = "are not an LCM event";
    } else if (got < kHeaderSize) {
      problem(start, true, "truncated: the event at offset " + std::to_string(start) + " ends inside its header (" +
                               std::to_string(got) + " of " + std::to_string(kHeaderSize) + " bytes)");
      if (!open_next()) return false;
      continue;
    }
    int64_t number = static_cast<int64_t>(big_endian(header + 4, 8));
    int64_t timestamp = static_cast<int64_t>(big_endian(header + 12, 8));
    int32_t channel_length = static_cast<int32_t>(big_endian(header + 20, 4));
    int32_t data_length = static_cast<int32_t>(big_endian(header + 24, 4));
    if (damage.empty() && (channel_length <= 0 || channel_length > kMaxChannelLength || data_length < 0))
      damage = "start an event header with a channel of " + std::to_string(channel_length) + " and data of " +
               std::to_string(data_length) + " byte(s)";
    if (!damage.empty()) {
      bool found = resync(start + 1);
      problem(start, false,
              "corrupt: " + std::to_string(position_ - start) + " byte(s) at offset " + std::to_string(start) + " " +
                  damage + (found ? "; read on from the next event" : "; nothing readable after them"));
      if (!found && !open_next()) return false;
      continue;
    }
    uint64_t need = static_cast<uint64_t>(channel_length) + static_cast<uint64_t>(data_length);
    uint64_t file_left = sizes_[current_] - position_;
    if (need > file_left) {
      problem(start, true, "truncated: the event at offset " + std::to_string(start) + " needs " +
                               std::to_string(need) + " byte(s) after its header, the file has " +
                               std::to_string(file_left) + " (a torn last write)");
      if (!open_next()) return false;
      continue;
    }
    event.channel.resize(static_cast<size_t>(channel_length));
    event.data.resize(static_cast<size_t>(data_length));
    if (!read_exact(event.channel.data(), event.channel.size()) || !read_exact(event.data.data(), event.data.size())) {
      problem(start, true, "truncated: the file ended while reading the event at offset " + std::to_string(start));
      if (!open_next()) return false;
      continue;
    }
    event.number = number;
    event.timestamp_us = timestamp;
    event.file_index = current_;
    event.offset = start;
    return true;
  }
}

}  // namespace bricklayer::inspect
