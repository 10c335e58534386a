#include "bricklayer/inspect/mcap_export.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "bricklayer/inspect/json_schema.h"

extern char** environ;

namespace bricklayer::inspect {

namespace fs = std::filesystem;

namespace {

std::string hex(const std::vector<uint8_t>& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (uint8_t b : bytes) {
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

std::string hex64(int64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// Nanoseconds as text: MCAP times are 64-bit unsigned, beyond what a JSON number keeps exactly.
std::string ns_text(int64_t utime_us) { return std::to_string(utime_us < 0 ? 0 : utime_us) + "000"; }

}  // namespace

std::string default_mcap_js_dir() { return BRICKLAYER_INSPECT_JS_DIR; }

McapExport::McapExport(const LcmTypeSet& types, std::string out_file, Options options)
    : types_(types), out_file_(std::move(out_file)) {
  fs::path script = fs::path(options.js_dir) / "mcap_write.mjs";
  if (!fs::exists(script)) throw std::runtime_error("the MCAP writer " + script.string() + " is missing");
  if (!fs::exists(fs::path(options.js_dir) / "node_modules" / "@mcap" / "core"))
    throw std::runtime_error("@mcap/core is not installed in " + options.js_dir +
                             "/node_modules: run launch/setup (it runs npm ci there)");
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
  std::vector<std::string> args = {options.node, script.string(), out_file_};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int rc = posix_spawnp(&pid_, options.node.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    throw std::runtime_error("cannot start " + options.node + " (Node.js, for the MCAP writer): " + std::strerror(rc));
  }
  pipe_ = fds[1];
  ::signal(SIGPIPE, SIG_IGN);  // a writer that died is reported by finish(), not by a signal here
}

McapExport::~McapExport() {
  if (!finished_) {
    try {
      finish();
    } catch (...) {
    }
  }
}

void McapExport::send(char kind, const Json& header, const void* body, size_t body_size) {
  if (pipe_ < 0) return;
  std::string h = header.dump(-1, ' ', false, Json::error_handler_t::replace);
  uint32_t total = static_cast<uint32_t>(4 + h.size() + body_size);
  std::string frame;
  frame.reserve(9 + h.size());
  frame += kind;
  for (int i = 3; i >= 0; --i) frame += static_cast<char>((total >> (8 * i)) & 0xff);
  uint32_t hl = static_cast<uint32_t>(h.size());
  for (int i = 3; i >= 0; --i) frame += static_cast<char>((hl >> (8 * i)) & 0xff);
  frame += h;
  auto write_all = [&](const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    while (n > 0) {
      ssize_t w = ::write(pipe_, c, n);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        ::close(pipe_);
        pipe_ = -1;  // the writer is gone: finish() reports why
        return;
      }
      c += w;
      n -= static_cast<size_t>(w);
    }
  };
  write_all(frame.data(), frame.size());
  if (body_size && pipe_ >= 0) write_all(body, body_size);
}

int McapExport::channel_for(const std::string& topic, const std::string& schema_key, const Json& schema_frame) {
  std::string key = topic + '\0' + schema_key;
  auto it = channels_.find(key);
  if (it != channels_.end()) return it->second;
  auto s = schemas_.find(schema_key);
  if (s == schemas_.end()) {
    int id = static_cast<int>(schemas_.size()) + 1;
    Json frame = schema_frame;
    frame["id"] = id;
    send('S', frame);
    s = schemas_.emplace(schema_key, id).first;
  }
  int id = static_cast<int>(channels_.size()) + 1;
  send('C', Json{{"id", id}, {"schema", s->second}, {"topic", topic}});
  channels_[key] = id;
  return id;
}

void McapExport::emit_images(const DecodedEvent& e, const LcmStruct& type, const Json& value, const std::string& path) {
  if (type.full_name() == kImageType) {
    const std::string topic = e.event.channel + "/" + (path.empty() ? "image" : path);
    int32_t format = value.at("format").get<int32_t>();
    const auto& bytes = value.at("data").get_binary();
    int64_t utime = value.at("utime").get<int64_t>();
    if (utime <= 0) utime = e.event.timestamp_us;
    std::string source = value.at("source").get<std::string>();
    Json header = {{"t", ns_text(utime)}, {"p", ns_text(e.event.timestamp_us)}, {"sec", utime / 1000000},
                   {"nsec", (utime % 1000000) * 1000}, {"frame_id", source.empty() ? e.event.channel : source}};
    if (format == 1 || format == 2) {
      int c = channel_for(topic, "foxglove.CompressedImage", Json{{"foxglove", "CompressedImage"}});
      header["c"] = c;
      header["s"] = sequences_[c]++;
      header["format"] = format == 1 ? "jpeg" : "png";
      send('I', header, bytes.data(), bytes.size());
    } else if (format == 3 || format == 4) {
      int c = channel_for(topic, "foxglove.RawImage", Json{{"foxglove", "RawImage"}});
      header["c"] = c;
      header["s"] = sequences_[c]++;
      header["width"] = value.at("width");
      header["height"] = value.at("height");
      header["encoding"] = format == 3 ? "mono8" : "bgr8";
      header["step"] = value.at("width").get<int64_t>() * (format == 3 ? 1 : 3);
      send('R', header, bytes.data(), bytes.size());
    } else {
      ++images_without_format_;
      return;
    }
    ++messages_;
    return;
  }
  for (const auto& m : type.members) {
    if (m.is_primitive()) continue;
    const LcmStruct* nested = types_.find(m.type);
    const Json& v = value.at(m.name);
    std::string p = path.empty() ? m.name : path + "." + m.name;
    if (m.dimensions.empty()) {
      emit_images(e, *nested, v, p);
    } else if (m.dimensions.size() == 1) {
      for (size_t i = 0; i < v.size(); ++i) emit_images(e, *nested, v[i], p + "." + std::to_string(i));
    }
  }
}

void McapExport::add(const DecodedEvent& e) {
  if (pipe_ < 0) return;
  if (!e.message) {
    int c = channel_for(e.event.channel, "bricklayer.undecoded",
                        Json{{"name", "bricklayer.undecoded"},
                             {"schema", {{"$schema", "http://json-schema.org/draft-07/schema#"},
                                         {"title", "bricklayer.undecoded"},
                                         {"description", "An LCM message bricklayer-export could not decode: its bytes in hex."},
                                         {"type", "object"},
                                         {"properties",
                                          {{"fingerprint", {{"type", "string"}}},
                                           {"type", {{"type", "string"}}},
                                           {"reason", {{"type", "string"}}},
                                           {"data_hex", {{"type", "string"}}}}},
                                         {"required", {"fingerprint", "type", "reason", "data_hex"}}}}});
    Json body = {{"fingerprint", hex64(e.fingerprint)},
                 {"type", e.type ? e.type->full_name() : ""},
                 {"reason", e.error},
                 {"data_hex", hex(e.event.data)}};
    std::string text = body.dump(-1, ' ', false, Json::error_handler_t::replace);
    send('M', Json{{"c", c}, {"s", sequences_[c]++}, {"t", ns_text(e.event.timestamp_us)}, {"p", ns_text(e.event.timestamp_us)}},
         text.data(), text.size());
    ++messages_;
    return;
  }
  const LcmStruct& type = *e.type;
  int c = channel_for(e.event.channel, type.full_name(), Json{{"name", type.full_name()}, {"schema", json_schema(types_, type)}});
  // The message's own time; a message without one (or with 0: a tool that left it unset) takes the
  // logger's receive time, so it does not land at 1970 on the timeline.
  int64_t log_time = e.event.timestamp_us;
  if (e.message->contains("utime") && e.message->at("utime").is_number_integer() && e.message->at("utime").get<int64_t>() > 0)
    log_time = e.message->at("utime").get<int64_t>();
  std::string text = mcap_json(types_, type, *e.message).dump(-1, ' ', false, Json::error_handler_t::replace);
  send('M', Json{{"c", c}, {"s", sequences_[c]++}, {"t", ns_text(log_time)}, {"p", ns_text(e.event.timestamp_us)}},
       text.data(), text.size());
  ++messages_;
  emit_images(e, type, *e.message, "");
}

void McapExport::finish() {
  if (finished_) return;
  finished_ = true;
  bool writer_gone = pipe_ < 0;
  if (pipe_ >= 0) {
    send('E', Json::object());
    if (pipe_ < 0) writer_gone = true;
    else ::close(pipe_);
    pipe_ = -1;
  }
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || writer_gone)
    throw std::runtime_error("the MCAP writer failed (" +
                             (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                                : "killed by signal " + std::to_string(WTERMSIG(status))) +
                             "); " + out_file_ + " is incomplete");
}

}  // namespace bricklayer::inspect
