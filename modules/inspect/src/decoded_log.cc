#include "bricklayer/inspect/decoded_log.h"

#include <sstream>

#include "bricklayer/inspect/progress.h"

namespace bricklayer::inspect {

std::string ReadSummary::describe() const {
  std::ostringstream out;
  out << events << " events, " << decoded << " decoded, " << unknown_type << " of unknown types, " << malformed
      << " malformed";
  for (const auto& p : problems) out << "\n  " << p.file << ": " << p.what;
  return out.str();
}

ReadSummary read_decoded(const std::vector<std::string>& files, const LcmTypeSet& types,
                         const std::function<void(const DecodedEvent&)>& on_event, const std::string& progress_program,
                         double progress_seconds) {
  LogSource source(files);
  Progress progress(progress_program, source.total_bytes(), !progress_program.empty(), progress_seconds);
  ReadSummary summary;
  LogEvent event;
  std::string error;
  uint64_t count = 0;
  while (source.next(event)) {
    ++summary.events;
    const LcmStruct* type = nullptr;
    int64_t fingerprint = 0;
    Json message;
    bool ok = false;
    error.clear();
    if (event.data.size() < 8) {
      error = "message of " + std::to_string(event.data.size()) + " byte(s) is shorter than a fingerprint";
      ++summary.malformed;
    } else {
      fingerprint = message_fingerprint(event.data.data(), event.data.size());
      type = types.find_by_fingerprint(fingerprint);
      if (!type) {
        error = "unknown type";
        ++summary.unknown_type;
      } else {
        try {
          message = decode_message(types, *type, event.data.data(), event.data.size());
          ok = true;
          ++summary.decoded;
        } catch (const DecodeError& e) {
          error = e.what();
          ++summary.malformed;
        }
      }
    }
    on_event(DecodedEvent{event, type, ok ? &message : nullptr, error, fingerprint});
    if ((++count & 255) == 0) progress.update(source.bytes_read());
  }
  progress.finish();
  summary.problems = source.problems();
  return summary;
}

}  // namespace bricklayer::inspect
