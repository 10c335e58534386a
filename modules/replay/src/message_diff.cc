#include "bricklayer/replay/message_diff.h"

#include <algorithm>
#include <cstring>
#include <regex>
#include <tuple>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/lcm_schema.h"

namespace bricklayer::replay {
namespace {

using inspect::Json;

int64_t read_i64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = v << 8 | p[i];
  return static_cast<int64_t>(v);
}

const inspect::LcmStruct* type_at(const uint8_t* data, size_t size) {
  if (size < 8) return nullptr;
  return inspect::builtin_types().find_by_fingerprint(read_i64(data));
}

std::string text(const Json& v) {
  if (v.is_binary()) return std::to_string(v.get_binary().size()) + " bytes";
  if (v.is_string()) return v.get<std::string>();
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

// Index-free path: "blocks[3].state" -> "blocks[].state".
std::string generic(const std::string& path) {
  static const std::regex index(R"(\[\d+\])");
  return std::regex_replace(path, index, "[]");
}

// image_t's format values (lcmtypes/image_t.lcm).
constexpr int kFormatJpeg = 1, kFormatPng = 2;

// An encoded picture is compared as the picture it decodes to: the same pixels encode to other bytes
// with another encoder build (libjpeg-turbo's SIMD paths, zlib's level), so bytes that differ are
// decoded and compared pixel by pixel: PNG exactly, JPEG within kJpegTolerance levels. "" when equal.
std::string picture_difference(const Json& image_a, const Json& image_b) {
  const auto& da = image_a.at("data").get_binary();
  const auto& db = image_b.at("data").get_binary();
  const int format = image_a.at("format").get<int>();
  const cv::Mat a = cv::imdecode(cv::Mat(1, static_cast<int>(da.size()), CV_8U, const_cast<uint8_t*>(da.data())), cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imdecode(cv::Mat(1, static_cast<int>(db.size()), CV_8U, const_cast<uint8_t*>(db.data())), cv::IMREAD_UNCHANGED);
  if (a.empty() || b.empty()) return std::string(a.empty() ? "the log's" : "the replay's") + " picture does not decode";
  if (a.size() != b.size() || a.type() != b.type())
    return "pictures of " + std::to_string(a.cols) + "x" + std::to_string(a.rows) + " vs " + std::to_string(b.cols) + "x" +
           std::to_string(b.rows);
  double worst = 0;
  cv::Point at;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::minMaxLoc(diff.reshape(1, diff.rows), nullptr, &worst, nullptr, &at);
  const double tolerance = format == kFormatJpeg ? MessageDiff::kJpegTolerance : 0;
  if (worst <= tolerance) return "";
  return "pixels differ by up to " + std::to_string(static_cast<int>(worst)) + " levels (at x " +
         std::to_string(at.x / std::max(1, a.channels())) + ", y " + std::to_string(at.y) + ")";
}

bool is_picture(const Json& j) {
  if (!j.is_object() || !j.contains("data") || !j.contains("format") || !j.at("data").is_binary()) return false;
  const Json& f = j.at("format");
  return f.is_number_integer() && (f.get<int>() == kFormatJpeg || f.get<int>() == kFormatPng);
}

void walk(const Json& a, const Json& b, const std::string& path, std::vector<FieldDifference>& out,
          const std::function<bool(const std::string&)>& skip) {
  if (skip(path)) return;
  if (is_picture(a) && is_picture(b) && a.at("format") == b.at("format") && a.at("data") != b.at("data")) {
    const std::string p = path.empty() ? "data" : path + ".data";
    if (!skip(p)) {
      const std::string d = picture_difference(a, b);
      if (!d.empty()) out.push_back({p, "the recorded picture", d});
    }
    // The other fields as usual; size follows the bytes.
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (it.key() == "data" || it.key() == "size" || !b.contains(it.key())) continue;
      walk(it.value(), b.at(it.key()), path.empty() ? it.key() : path + "." + it.key(), out, skip);
    }
    return;
  }
  if (a.is_object() && b.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      const std::string p = path.empty() ? it.key() : path + "." + it.key();
      if (!b.contains(it.key())) {
        if (!skip(p)) out.push_back({p, text(it.value()), "(absent)"});
        continue;
      }
      walk(it.value(), b.at(it.key()), p, out, skip);
    }
    return;
  }
  if (a.is_array() && b.is_array()) {
    const size_t n = std::min(a.size(), b.size());
    for (size_t i = 0; i < n; ++i) walk(a[i], b[i], path + "[" + std::to_string(i) + "]", out, skip);
    if (a.size() != b.size() && !skip(path + "[]"))
      out.push_back({path + ".size", std::to_string(a.size()), std::to_string(b.size())});
    return;
  }
  if (a != b) out.push_back({path, text(a), text(b)});
}

}  // namespace

bool MessageKey::operator<(const MessageKey& o) const {
  return std::tie(channel, utime, frame_number) < std::tie(o.channel, o.utime, o.frame_number);
}
bool MessageKey::operator==(const MessageKey& o) const {
  return channel == o.channel && utime == o.utime && frame_number == o.frame_number;
}

MessageDiff::MessageDiff(std::vector<std::string> ignored) : ignored_(std::move(ignored)) {}

std::string MessageDiff::type_of(const uint8_t* data, size_t size) const {
  const auto* t = type_at(data, size);
  return t ? t->name : "";
}

std::optional<MessageKey> MessageDiff::key(const std::string& channel, const uint8_t* data, size_t size) const {
  const auto* t = type_at(data, size);
  if (!t || t->members.empty() || t->members[0].name != "utime" || size < 16) return std::nullopt;
  MessageKey k{channel, read_i64(data + 8), -1};
  if (t->members.size() > 1 && t->members[1].name == "frame_number" && t->members[1].type == "int64_t" && size >= 24)
    k.frame_number = read_i64(data + 16);
  return k;
}

bool MessageDiff::ignores_type(const std::string& type) const {
  return std::find(ignored_.begin(), ignored_.end(), type) != ignored_.end();
}

bool MessageDiff::ignored_path(const std::string& type, const std::string& path) const {
  if (path.empty()) return false;
  const std::string full = type + "." + generic(path);
  for (const auto& i : ignored_)
    if (full == i || full.compare(0, i.size() + 1, i + ".") == 0 || full.compare(0, i.size() + 1, i + "[") == 0) return true;
  return false;
}

std::vector<FieldDifference> MessageDiff::differences(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) const {
  if (a == b) return {};
  const auto* ta = type_at(a.data(), a.size());
  const auto* tb = type_at(b.data(), b.size());
  if (!ta || ta != tb) return {{"", ta ? ta->name : "not a known message", tb ? tb->name : "not a known message"}};
  if (ignores_type(ta->name)) return {};
  Json ja, jb;
  try {
    ja = inspect::decode_message(inspect::builtin_types(), *ta, a.data(), a.size());
  } catch (const std::exception& e) {
    return {{"", std::string("does not decode: ") + e.what(), "decodes"}};
  }
  try {
    jb = inspect::decode_message(inspect::builtin_types(), *tb, b.data(), b.size());
  } catch (const std::exception& e) {
    return {{"", "decodes", std::string("does not decode: ") + e.what()}};
  }
  std::vector<FieldDifference> out;
  walk(ja, jb, "", out, [&](const std::string& p) { return ignored_path(ta->name, p); });
  return out;
}

std::string MessageDiff::describe(const std::vector<FieldDifference>& d, const std::string& a_name,
                                  const std::string& b_name, size_t max) {
  std::string out;
  for (size_t i = 0; i < d.size() && i < max; ++i) {
    if (!out.empty()) out += "; ";
    out += (d[i].path.empty() ? std::string("message") : d[i].path) + ": " + d[i].a + " (" + a_name + ") vs " + d[i].b +
           " (" + b_name + ")";
  }
  if (d.size() > max) out += "; +" + std::to_string(d.size() - max) + " more";
  return out;
}

}  // namespace bricklayer::replay
