// bricklayer-export --csv / --jsonl: one file per message kind (channel), written as the log streams
// past (nothing but the open files is held). CSV rows follow TableLayout; a JSONL line is the whole
// decoded message under "message" with the event's number, log time and channel, byte arrays left out
// and every microsecond time given a "..._utc" twin. Messages that could not be decoded go to
// undecoded.csv / undecoded.jsonl with the reason; index.csv lists every file with its message and
// row counts.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "bricklayer/inspect/decoded_log.h"
#include "bricklayer/inspect/table_layout.h"

namespace bricklayer::inspect {

class FileExport {
 public:
  enum class Format { kCsv, kJsonl };
  // Creates `dir` when missing; throws std::runtime_error when it cannot be written.
  FileExport(const LcmTypeSet& types, std::string dir, Format format);
  ~FileExport();

  void add(const DecodedEvent& e);
  // Closes every file and writes index.csv; throws on a write error (disk full).
  void finish();

  struct Kind {
    std::string channel;
    std::string type;
    std::string file;
    uint64_t messages = 0;
    uint64_t rows = 0;
  };
  const std::map<std::string, Kind>& kinds() const { return kinds_; }

 private:
  struct Output {
    std::ofstream out;
    std::unique_ptr<TableLayout> layout;
    Kind* kind = nullptr;
  };
  Output& output_for(const std::string& key, const std::string& channel, const std::string& type_name,
                     const LcmStruct* type);
  std::string file_name_for(const std::string& channel, const std::string& type_name);

  const LcmTypeSet& types_;
  std::string dir_;
  Format format_;
  std::map<std::string, Kind> kinds_;
  std::map<std::string, Output> outputs_;
  std::map<std::string, std::string> used_files_;
};

// The message as JSONL writes it: byte arrays dropped, "<time>_utc" next to every microsecond time.
Json readable_json(const Json& message);

}  // namespace bricklayer::inspect
