#include "bricklayer/inspect/log_source.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "bricklayer/runtime/log_file.h"

namespace bricklayer::inspect {

LogSource::LogSource(std::vector<std::string> files) : files_(std::move(files)) {
  for (const auto& f : files_) {
    struct stat st {};
    if (::stat(f.c_str(), &st) != 0) throw LogOpenError("cannot read log " + f + ": " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw LogOpenError("log " + f + " is not a regular file");
    try {
      runtime::LogReader probe(f);  // unreadable (permissions): say so now, before any output exists
    } catch (const std::runtime_error& e) {
      throw LogOpenError(e.what());
    }
    sizes_.push_back(static_cast<uint64_t>(st.st_size));
    total_bytes_ += static_cast<uint64_t>(st.st_size);
  }
}

LogSource::~LogSource() = default;

void LogSource::take_damage() {
  const auto& damage = reader_->damage();
  for (; damage_seen_ < damage.size(); ++damage_seen_) {
    const runtime::LogDamage& d = damage[damage_seen_];
    problems_.push_back({files_[current_], static_cast<uint64_t>(d.offset), d.at_end,
                         std::string(d.at_end ? "truncated: " : "corrupt: ") + d.describe()});
  }
}

bool LogSource::next(LogEvent& event) {
  while (current_ < files_.size()) {
    if (!reader_) {
      try {
        reader_ = std::make_unique<runtime::LogReader>(files_[current_]);
      } catch (const std::runtime_error& e) {
        throw LogOpenError(e.what());
      }
      damage_seen_ = 0;
    }
    runtime::LogEvent e;
    bool got = reader_->next(e);
    take_damage();
    position_ = static_cast<uint64_t>(reader_->position());
    if (got) {
      event.number = e.number;
      event.timestamp_us = e.utime;
      event.channel = std::move(e.channel);
      event.data = std::move(e.data);
      event.file_index = current_;
      event.offset = static_cast<uint64_t>(e.offset);
      return true;
    }
    reader_.reset();
    done_bytes_ += sizes_[current_];
    position_ = 0;
    ++current_;
  }
  return false;
}

}  // namespace bricklayer::inspect
