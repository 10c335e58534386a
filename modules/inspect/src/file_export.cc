#include "bricklayer/inspect/file_export.h"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "bricklayer/inspect/wall_clock.h"

namespace bricklayer::inspect {

namespace fs = std::filesystem;

namespace {

std::string safe_file_part(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.') ? c : '_';
  if (out.empty() || out[0] == '.') out = "_" + out;
  return out;
}

std::string hex64(int64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(v));
  return buf;
}

const char* const kUndecodedKey = "\x01undecoded";

}  // namespace

Json readable_json(const Json& v) {
  if (v.is_object()) {
    Json out = Json::object();
    for (auto it = v.begin(); it != v.end(); ++it) {
      if (it.value().is_binary()) continue;
      out[it.key()] = readable_json(it.value());
      if (is_utime_name(it.key()) && it.value().is_number_integer())
        out[it.key() + "_utc"] = utc_text(it.value().get<int64_t>());
    }
    return out;
  }
  if (v.is_array()) {
    Json out = Json::array();
    for (const auto& e : v) out.push_back(readable_json(e));
    return out;
  }
  return v;
}

FileExport::FileExport(const LcmTypeSet& types, std::string dir, Format format)
    : types_(types), dir_(std::move(dir)), format_(format) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) throw std::runtime_error("cannot create the output folder " + dir_ + ": " + ec.message());
}

FileExport::~FileExport() = default;

std::string FileExport::file_name_for(const std::string& channel, const std::string& type_name) {
  std::string ext = format_ == Format::kCsv ? ".csv" : ".jsonl";
  std::string base = safe_file_part(channel);
  std::string name = base + ext;
  if (used_files_.count(name)) name = base + "." + safe_file_part(type_name) + ext;
  for (int i = 2; used_files_.count(name); ++i) name = base + "." + std::to_string(i) + ext;
  used_files_[name] = channel;
  return name;
}

FileExport::Output& FileExport::output_for(const std::string& key, const std::string& channel,
                                           const std::string& type_name, const LcmStruct* type) {
  auto it = outputs_.find(key);
  if (it != outputs_.end()) return it->second;
  Kind& kind = kinds_[key];
  kind.channel = channel;
  kind.type = type_name;
  kind.file = key == kUndecodedKey ? (format_ == Format::kCsv ? "undecoded.csv" : "undecoded.jsonl")
                                   : file_name_for(channel, type_name);
  if (key == kUndecodedKey) used_files_[kind.file] = "";
  Output& o = outputs_[key];
  o.kind = &kind;
  o.out.open(fs::path(dir_) / kind.file, std::ios::binary | std::ios::trunc);
  if (!o.out) throw std::runtime_error("cannot write " + (fs::path(dir_) / kind.file).string());
  if (format_ == Format::kCsv) {
    std::vector<std::string> header;
    if (type) {
      o.layout = std::make_unique<TableLayout>(types_, *type);
      header = o.layout->header();
    } else {
      header = {"event", "log_utime_us", "log_utc", "channel", "fingerprint", "type", "size_bytes", "reason"};
    }
    for (size_t i = 0; i < header.size(); ++i) o.out << (i ? "," : "") << csv_quote(header[i]);
    o.out << "\n";
  }
  return o;
}

void FileExport::add(const DecodedEvent& e) {
  if (e.message) {
    const std::string type_name = e.type->full_name();
    Output& o = output_for(e.event.channel + '\0' + type_name, e.event.channel, type_name, e.type);
    ++o.kind->messages;
    if (format_ == Format::kCsv) {
      for (const auto& row : o.layout->rows(e.event, *e.message)) {
        for (size_t i = 0; i < row.size(); ++i) o.out << (i ? "," : "") << csv_quote(row[i]);
        o.out << "\n";
        ++o.kind->rows;
      }
    } else {
      Json line = Json::object();
      line["event"] = e.event.number;
      line["log_utime_us"] = e.event.timestamp_us;
      line["log_utc"] = utc_text(e.event.timestamp_us);
      line["channel"] = e.event.channel;
      line["type"] = type_name;
      line["message"] = readable_json(*e.message);
      o.out << line.dump(-1, ' ', false, Json::error_handler_t::replace) << "\n";
      ++o.kind->rows;
    }
    return;
  }
  Output& o = output_for(kUndecodedKey, "", "", nullptr);
  ++o.kind->messages;
  ++o.kind->rows;
  std::string type = e.type ? e.type->full_name() : "";
  if (format_ == Format::kCsv) {
    std::vector<std::string> row = {std::to_string(e.event.number), std::to_string(e.event.timestamp_us),
                                    utc_text(e.event.timestamp_us), e.event.channel, hex64(e.fingerprint), type,
                                    std::to_string(e.event.data.size()), e.error};
    for (size_t i = 0; i < row.size(); ++i) o.out << (i ? "," : "") << csv_quote(row[i]);
    o.out << "\n";
  } else {
    Json line = {{"event", e.event.number},          {"log_utime_us", e.event.timestamp_us},
                 {"log_utc", utc_text(e.event.timestamp_us)}, {"channel", e.event.channel},
                 {"fingerprint", hex64(e.fingerprint)}, {"type", type},
                 {"size_bytes", e.event.data.size()},  {"reason", e.error}};
    o.out << line.dump(-1, ' ', false, Json::error_handler_t::replace) << "\n";
  }
}

void FileExport::finish() {
  std::string failed;
  for (auto& [key, o] : outputs_) {
    o.out.close();
    if (!o.out) failed += " " + o.kind->file;
  }
  std::ofstream index(fs::path(dir_) / "index.csv", std::ios::trunc);
  index << "file,channel,type,messages,rows\n";
  for (const auto& [key, k] : kinds_)
    index << csv_quote(k.file) << "," << csv_quote(k.channel) << "," << csv_quote(k.type) << "," << k.messages << ","
          << k.rows << "\n";
  index.close();
  if (!index) failed += " index.csv";
  if (!failed.empty()) throw std::runtime_error("could not write (disk full?):" + failed + " in " + dir_);
}

}  // namespace bricklayer::inspect
