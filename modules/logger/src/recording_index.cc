#include "bricklayer/logger/recording_index.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer::logger {
namespace fs = std::filesystem;
using nlohmann::json;

IndexWriter::IndexWriter(std::string path) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot open the recording index " + path_ + ": " + std::strerror(errno));
}

IndexWriter::~IndexWriter() {
  if (fd_ >= 0) {
    ::fsync(fd_);
    ::close(fd_);
  }
}

void IndexWriter::line(const std::string& text) {
  const std::string l = text + "\n";
  const off_t before = ::lseek(fd_, 0, SEEK_END);
  size_t done = 0;
  while (done < l.size()) {
    const ssize_t n = ::write(fd_, l.data() + done, l.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;
    }
  }
  if (done == l.size()) {
    bytes_ += static_cast<int64_t>(done);
    return;
  }
  ++failed_;
  if (done > 0 && before >= 0) {
    if (::ftruncate(fd_, before) != 0) {
      // Cannot cut the torn line off: the reader skips it.
    }
  }
}

void IndexWriter::part(const std::string& part_path, int64_t first_utime) {
  line(json{{"part", fs::path(part_path).filename().string()}, {"t", first_utime}}.dump());
}

void IndexWriter::seek(const std::string& part_path, int64_t utime, int64_t offset) {
  line(json{{"seek", utime}, {"part", fs::path(part_path).filename().string()}, {"offset", offset}}.dump());
}

void IndexWriter::moment(const Moment& m) { line(json{{"moment", m.kind}, {"t", m.utime}, {"note", m.note}}.dump()); }

void IndexWriter::loss(const Loss& l) {
  line(json{{"loss", l.events}, {"from", l.from_utime}, {"to", l.to_utime}, {"reason", l.reason}}.dump());
}

std::string RecordingIndex::path_for(const std::string& part_path) {
  const auto dot = part_path.rfind('.');
  if (dot == std::string::npos || dot + 1 == part_path.size()) return "";
  const std::string suffix = part_path.substr(dot + 1);
  if (!std::all_of(suffix.begin(), suffix.end(), [](char c) { return c >= '0' && c <= '9'; })) return "";
  return part_path.substr(0, dot) + ".index";
}

RecordingIndex RecordingIndex::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the recording index " + path);
  const fs::path folder = fs::path(path).parent_path();
  RecordingIndex index;
  std::string text;
  while (std::getline(in, text)) {
    if (text.empty()) continue;
    try {
      const json j = json::parse(text);
      if (j.contains("seek")) {
        index.seeks_.push_back({j.at("seek").get<int64_t>(), (folder / j.at("part").get<std::string>()).string(),
                                j.at("offset").get<int64_t>()});
      } else if (j.contains("part")) {
        const std::string part = (folder / j.at("part").get<std::string>()).string();
        if (std::find(index.parts_.begin(), index.parts_.end(), part) == index.parts_.end()) index.parts_.push_back(part);
        index.seeks_.push_back({j.at("t").get<int64_t>(), part, 0});
      } else if (j.contains("moment")) {
        index.moments_.push_back({j.at("t").get<int64_t>(), j.at("moment").get<std::string>(), j.value("note", "")});
      } else if (j.contains("loss")) {
        index.losses_.push_back({j.at("loss").get<int64_t>(), j.at("from").get<int64_t>(), j.at("to").get<int64_t>(),
                                 j.value("reason", "")});
      } else {
        ++index.unreadable_;
      }
    } catch (const json::exception&) {
      ++index.unreadable_;  // a line torn by a crash, or not ours
    }
  }
  std::stable_sort(index.seeks_.begin(), index.seeks_.end(),
                   [](const SeekPoint& a, const SeekPoint& b) { return a.utime < b.utime; });
  return index;
}

std::optional<SeekPoint> RecordingIndex::seek(int64_t utime) const {
  if (seeks_.empty()) return std::nullopt;
  auto it = std::upper_bound(seeks_.begin(), seeks_.end(), utime,
                             [](int64_t t, const SeekPoint& s) { return t < s.utime; });
  if (it == seeks_.begin()) return seeks_.front();
  return *std::prev(it);
}

std::vector<std::string> RecordingIndex::parts() const { return parts_; }

}  // namespace bricklayer::logger
