// bricklayer-export --mcap: the whole log as an MCAP file Foxglove opens. The MCAP itself is written
// by Foxglove's reference implementation (@mcap/core, run by Node.js: js/mcap_write.mjs); this class
// decides what goes in and streams it to that process through a pipe (the pipe's back-pressure keeps
// memory flat whatever the log's size):
// - every message as JSON on a topic named after its channel, with a JSON Schema generated from its
//   .lcm definition (json_schema.h); log time = the message's utime, publish time = the logger's
//   receive time (both the receive time when a message has no utime or leaves it 0);
// - the bytes of every image_t (camera frames, the projector's image inside projector_state_t) on
//   CHANNEL/image as foxglove.CompressedImage (JPEG, PNG) or foxglove.RawImage (GRAY8, BGR8);
// - messages that could not be decoded on their channel under the schema bricklayer.undecoded, with
//   their bytes in hex and the reason.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <map>
#include <string>

#include "bricklayer/inspect/decoded_log.h"

namespace bricklayer::inspect {

// Where js/ was at build time (the MCAP scripts and their node_modules, installed by launch/setup).
std::string default_mcap_js_dir();

class McapExport {
 public:
  struct Options {
    std::string node = "node";
    std::string js_dir;
  };
  // Starts the writer process; throws std::runtime_error when it cannot (no Node.js, no node_modules).
  McapExport(const LcmTypeSet& types, std::string out_file, Options options);
  ~McapExport();
  McapExport(const McapExport&) = delete;
  McapExport& operator=(const McapExport&) = delete;

  void add(const DecodedEvent& e);
  // Ends the stream and waits for the writer to finish the file's summary; throws when it failed.
  void finish();

  uint64_t messages() const { return messages_; }
  size_t channels() const { return channels_.size(); }
  uint64_t images_without_format() const { return images_without_format_; }

 private:
  int channel_for(const std::string& topic, const std::string& schema_key, const Json& schema_frame);
  void emit_images(const DecodedEvent& e, const LcmStruct& type, const Json& value, const std::string& path);
  void send(char kind, const Json& header, const void* body = nullptr, size_t body_size = 0);

  const LcmTypeSet& types_;
  std::string out_file_;
  pid_t pid_ = -1;
  int pipe_ = -1;
  bool finished_ = false;
  std::map<std::string, int> schemas_;
  std::map<std::string, int> channels_;
  std::map<int, uint32_t> sequences_;
  uint64_t messages_ = 0;
  uint64_t images_without_format_ = 0;
};

}  // namespace bricklayer::inspect
