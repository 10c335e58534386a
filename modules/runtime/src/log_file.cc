#include "bricklayer/runtime/log_file.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace bricklayer::runtime {
namespace {

uint32_t read_u32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}
uint64_t read_u64(const uint8_t* p) { return (uint64_t{read_u32(p)} << 32) | read_u32(p + 4); }
void put_u32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}
void put_u64(uint8_t* p, uint64_t v) {
  put_u32(p, static_cast<uint32_t>(v >> 32));
  put_u32(p + 4, static_cast<uint32_t>(v));
}

}  // namespace

std::string LogDamage::describe() const {
  return std::to_string(bytes) + " bytes at offset " + std::to_string(offset) +
         (at_end ? " (the file ends inside an event: truncated)" : " held no intact event (torn or corrupt)");
}

LogReader::LogReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw std::runtime_error("cannot open the log '" + path + "': " + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  if (fseeko(file_, 0, SEEK_END) == 0) size_ = ftello(file_);
  fseeko(file_, 0, SEEK_SET);
}

LogReader::~LogReader() {
  if (file_) std::fclose(file_);
}

bool LogReader::read_at(int64_t offset, void* out, size_t bytes) {
  if (offset < 0 || offset + static_cast<int64_t>(bytes) > size_) return false;
  if (ftello(file_) != offset && fseeko(file_, offset, SEEK_SET) != 0) return false;
  return std::fread(out, 1, bytes, file_) == bytes;
}

bool LogReader::plausible_header_at(int64_t offset, Header& h) {
  uint8_t b[kLogEventHeaderBytes];
  if (!read_at(offset, b, sizeof(b))) return false;
  if (read_u32(b) != kLogSyncWord) return false;
  h.number = static_cast<int64_t>(read_u64(b + 4));
  h.utime = static_cast<int64_t>(read_u64(b + 12));
  h.channel_bytes = static_cast<int32_t>(read_u32(b + 20));
  h.data_bytes = static_cast<int32_t>(read_u32(b + 24));
  return h.channel_bytes >= 1 && h.channel_bytes <= kMaxLogChannelBytes && h.data_bytes >= 0;
}

// An event is intact when its header is plausible, it fits in the file, its channel is printable, and
// no intact event starts inside it: a torn event (a write cut short, then more events appended) has a
// length that runs into the events after it. Bytes after an intact event that are not a sync word
// are junk of their own, skipped when reading on.
bool LogReader::intact_event_at(int64_t offset, Header& h, bool strict) {
  if (!plausible_header_at(offset, h)) return false;
  const int64_t end = offset + kLogEventHeaderBytes + h.channel_bytes + h.data_bytes;
  if (end > size_) return false;
  std::string channel(static_cast<size_t>(h.channel_bytes), '\0');
  if (!read_at(offset + kLogEventHeaderBytes, channel.data(), channel.size())) return false;
  if (!std::all_of(channel.begin(), channel.end(), [](char c) { return c >= 0x20 && c < 0x7f; })) return false;
  if (end + 4 <= size_) {
    uint8_t sync[4];
    if (read_at(end, sync, 4) && read_u32(sync) == kLogSyncWord) return true;
  }
  if (end == size_) return true;
  // Not followed by an event: either junk follows an intact event, or this one is torn. (The events
  // looked for inside it must be followed by an event themselves: one level, so a scan stays linear.)
  return !strict && find_event_in(offset + 1, end, true) < 0;
}

int64_t LogReader::find_event_in(int64_t from, int64_t to, bool strict) {
  // Scan in blocks for the sync word's first byte, then check the candidate in full.
  std::vector<uint8_t> block(1 << 16);
  for (int64_t base = from; base < to;) {
    const size_t n = static_cast<size_t>(std::min<int64_t>(static_cast<int64_t>(block.size()), to - base));
    if (!read_at(base, block.data(), n)) return -1;
    for (size_t i = 0; i < n; ++i) {
      if (block[i] != 0xED) continue;
      Header h;
      const int64_t at = base + static_cast<int64_t>(i);
      if (intact_event_at(at, h, strict)) return at;
    }
    base += static_cast<int64_t>(n);
  }
  return -1;
}

bool LogReader::next(LogEvent& event) {
  while (position_ < size_) {
    Header h;
    if (!intact_event_at(position_, h, false)) {
      const int64_t found = find_event_in(position_ + 1, size_, false);
      const int64_t next = found < 0 ? size_ : found;
      // Reading again after a seek meets the same region: record it once.
      const int64_t at = position_;
      if (std::none_of(damage_.begin(), damage_.end(), [at](const LogDamage& d) { return d.offset == at; }))
        damage_.push_back(LogDamage{position_, next - position_, next >= size_});
      position_ = next;
      continue;
    }
    event.number = h.number;
    event.utime = h.utime;
    event.offset = position_;
    event.channel.assign(static_cast<size_t>(h.channel_bytes), '\0');
    event.data.resize(static_cast<size_t>(h.data_bytes));
    if (!read_at(position_ + kLogEventHeaderBytes, event.channel.data(), event.channel.size()) ||
        (h.data_bytes > 0 && !read_at(position_ + kLogEventHeaderBytes + h.channel_bytes, event.data.data(), event.data.size()))) {
      throw std::runtime_error("cannot read the log '" + path_ + "' at offset " + std::to_string(position_));
    }
    position_ += kLogEventHeaderBytes + h.channel_bytes + h.data_bytes;
    return true;
  }
  return false;
}

void LogReader::seek(int64_t offset) { position_ = std::clamp<int64_t>(offset, 0, size_); }

std::vector<uint8_t> encode_log_event(int64_t number, int64_t utime, const std::string& channel, const uint8_t* data,
                                      size_t size) {
  std::vector<uint8_t> out(static_cast<size_t>(kLogEventHeaderBytes) + channel.size() + size);
  put_u32(out.data(), kLogSyncWord);
  put_u64(out.data() + 4, static_cast<uint64_t>(number));
  put_u64(out.data() + 12, static_cast<uint64_t>(utime));
  put_u32(out.data() + 20, static_cast<uint32_t>(channel.size()));
  put_u32(out.data() + 24, static_cast<uint32_t>(size));
  std::memcpy(out.data() + kLogEventHeaderBytes, channel.data(), channel.size());
  if (size > 0) std::memcpy(out.data() + kLogEventHeaderBytes + channel.size(), data, size);
  return out;
}

LogWriter::LogWriter(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw std::runtime_error("cannot create the log '" + path + "': " + std::strerror(errno));
}

LogWriter::~LogWriter() {
  if (file_) std::fclose(file_);
}

bool LogWriter::write(int64_t utime, const std::string& channel, const uint8_t* data, size_t size) {
  if (channel.empty() || channel.size() > static_cast<size_t>(kMaxLogChannelBytes)) return false;
  const std::vector<uint8_t> bytes = encode_log_event(events_, utime, channel, data, size);
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) return false;
  ++events_;
  bytes_ += static_cast<int64_t>(bytes.size());
  return true;
}

bool LogWriter::flush() { return std::fflush(file_) == 0; }

}  // namespace bricklayer::runtime
