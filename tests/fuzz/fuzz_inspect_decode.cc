// Fuzz target: the exporters' generic decoder on arbitrary message bytes. The first byte picks one of
// the built-in types (its fingerprint is put in front, so the decoder reads past it), the rest is the
// message body. A decoded message must also flatten into CSV rows, the MCAP JSON form and JSON lines;
// anything else must be a DecodeError, never a crash or an allocation the bytes cannot back.
#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/inspect/file_export.h"
#include "bricklayer/inspect/json_schema.h"
#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/log_source.h"
#include "bricklayer/inspect/table_layout.h"

using namespace bricklayer::inspect;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (1 << 16)) return 0;
  const LcmTypeSet& types = builtin_types();
  std::vector<const LcmStruct*> all;
  for (const auto& [name, s] : types.structs()) all.push_back(&s);
  const LcmStruct& type = *all[data[0] % all.size()];
  std::vector<uint8_t> message(8);
  uint64_t fp = static_cast<uint64_t>(types.fingerprint(type.full_name()));
  for (int i = 0; i < 8; ++i) message[static_cast<size_t>(i)] = static_cast<uint8_t>(fp >> (56 - 8 * i));
  message.insert(message.end(), data + 1, data + size);
  Json decoded;
  try {
    decoded = decode_message(types, type, message.data(), message.size());
  } catch (const DecodeError&) {
    return 0;
  }
  LogEvent event;
  event.number = 1;
  event.timestamp_us = 1;
  TableLayout layout(types, type);
  for (const auto& row : layout.rows(event, decoded))
    if (row.size() != layout.header().size()) __builtin_trap();
  (void)mcap_json(types, type, decoded).dump(-1, ' ', false, Json::error_handler_t::replace);
  (void)readable_json(decoded).dump(-1, ' ', false, Json::error_handler_t::replace);
  return 0;
}
