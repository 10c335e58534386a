#include "bricklayer/replay/recording.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace bricklayer::replay {
namespace fs = std::filesystem;

RecordingReader::RecordingReader(const std::vector<std::string>& sources, int64_t from_utime) {
  if (sources.empty()) throw std::runtime_error("no log given");
  size_t start_part = 0;
  int64_t start_offset = 0;
  if (sources.size() == 1 && fs::path(sources[0]).extension() == ".index") {
    index_ = logger::RecordingIndex::load(sources[0]);
    for (const auto& p : index_->parts()) (fs::exists(p) ? parts_ : missing_).push_back(p);
    if (parts_.empty())
      throw std::runtime_error("the index " + sources[0] + " names no part that still exists (" +
                               std::to_string(missing_.size()) + " gone: deleted by the disk budget?)");
    if (from_utime > 0) {
      // The last seek point at or before the start whose part still exists.
      const logger::SeekPoint* best = nullptr;
      for (const auto& s : index_->seek_points())
        if (s.utime <= from_utime && std::find(parts_.begin(), parts_.end(), s.part) != parts_.end()) best = &s;
      if (best) {
        start_part = static_cast<size_t>(std::find(parts_.begin(), parts_.end(), best->part) - parts_.begin());
        start_offset = best->offset;
      }
    }
  } else {
    for (const auto& s : sources) {
      if (!fs::is_regular_file(s)) throw std::runtime_error("cannot read the log " + s + ": no such file");
      parts_.push_back(s);
    }
  }
  for (size_t i = 0; i < parts_.size(); ++i) {
    std::error_code ec;
    const auto size = static_cast<int64_t>(fs::file_size(parts_[i], ec));
    if (!ec) {
      total_bytes_ += size;
      if (i < start_part) done_before_ += size;
    }
  }
  if (!open(start_part, start_offset)) throw std::runtime_error("cannot read the log " + parts_[start_part]);
}

bool RecordingReader::open(size_t part, int64_t offset) {
  current_ = part;
  damage_seen_in_part_ = 0;
  reader_ = std::make_unique<runtime::LogReader>(parts_[part]);
  if (offset > 0) reader_->seek(offset);
  return true;
}

bool RecordingReader::next(runtime::LogEvent& e) {
  while (reader_) {
    const bool got = reader_->next(e);
    const auto& d = reader_->damage();
    for (; damage_seen_in_part_ < d.size(); ++damage_seen_in_part_) damage_.push_back({parts_[current_], d[damage_seen_in_part_], 0});
    if (got) {
      for (auto& pd : damage_) ++pd.events_after;
      return true;
    }
    done_before_ += reader_->size();
    if (current_ + 1 >= parts_.size()) {
      reader_.reset();
      return false;
    }
    open(current_ + 1, 0);
  }
  return false;
}

std::vector<PartDamage> RecordingReader::damage() const { return damage_; }

int64_t RecordingReader::done_bytes() const { return done_before_ + (reader_ ? reader_->position() : 0); }

}  // namespace bricklayer::replay
