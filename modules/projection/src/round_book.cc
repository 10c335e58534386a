#include "bricklayer/projection/round_book.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer::projection {

namespace {

constexpr int kVersion = 1;

nlohmann::json to_json(const RoundRecord& r, bool finished) {
  nlohmann::json j{{"start_utime", r.start_utime}, {"max_score", r.max_score}, {"blocks", r.blocks},
                   {"most_blocks", r.most_blocks}};
  if (finished) {
    j["end_utime"] = r.end_utime;
    j["end"] = round_end_name(r.end);
  }
  return j;
}

RoundRecord from_json(const nlohmann::json& j, bool finished) {
  if (!j.is_object()) throw std::runtime_error("a round is not a JSON object");
  RoundRecord r;
  r.start_utime = j.at("start_utime").get<int64_t>();
  r.max_score = j.at("max_score").get<int>();
  r.blocks = j.at("blocks").get<int>();
  r.most_blocks = j.at("most_blocks").get<int>();
  if (finished) {
    r.end_utime = j.at("end_utime").get<int64_t>();
    const auto end = parse_round_end(j.at("end").get<std::string>());
    if (!end) throw std::runtime_error("unknown round end '" + j.at("end").get<std::string>() + "'");
    r.end = *end;
    if (r.end_utime < r.start_utime) throw std::runtime_error("a round ends before it starts");
  }
  if (r.max_score < 0 || r.blocks < 0 || r.most_blocks < 0) throw std::runtime_error("a negative score or block count");
  return r;
}

std::string os_error(const std::string& what, const std::string& path) {
  return what + " '" + path + "': " + std::strerror(errno);
}

}  // namespace

RoundBook load_round_book(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(os_error("cannot read the round book", path));
  std::stringstream text;
  text << in.rdbuf();
  try {
    const nlohmann::json j = nlohmann::json::parse(text.str());
    if (!j.is_object() || j.value("version", 0) != kVersion)
      throw std::runtime_error("not a version " + std::to_string(kVersion) + " round book");
    RoundBook book;
    for (const auto& r : j.at("rounds")) book.history.push_back(from_json(r, true));
    if (j.contains("running") && !j.at("running").is_null()) book.running = from_json(j.at("running"), false);
    return book;
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("the round book '" + path + "' is damaged: " + e.what());
  } catch (const std::exception& e) {  // nlohmann's parse, type and missing-key errors
    throw std::runtime_error("the round book '" + path + "' is damaged: " + e.what());
  }
}

void save_round_book(const std::string& path, const RoundBook& book) {
  nlohmann::json j{{"version", kVersion}, {"rounds", nlohmann::json::array()}, {"running", nullptr}};
  for (const RoundRecord& r : book.history) j["rounds"].push_back(to_json(r, true));
  if (book.running) j["running"] = to_json(*book.running, false);
  const std::string text = j.dump(1) + "\n";

  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(os_error("cannot write the round book", tmp));
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = os_error("cannot write the round book", tmp);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error(why);
    }
    done += static_cast<size_t>(n);
  }
  // On the disk before the rename: a power cut must not leave the new name on empty content.
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = os_error("cannot flush the round book", tmp);
    ::unlink(tmp.c_str());
    throw std::runtime_error(why);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = os_error("cannot replace the round book", path);
    ::unlink(tmp.c_str());
    throw std::runtime_error(why);
  }
  // The rename itself is durable once its folder is flushed.
  const std::string folder = std::filesystem::path(path).parent_path().empty()
                                 ? std::string(".")
                                 : std::filesystem::path(path).parent_path().string();
  const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

}  // namespace bricklayer::projection
