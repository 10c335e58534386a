// Decodes any LCM message whose .lcm definition is known into a JSON value (members in declaration
// order), without the generated C++ classes: what lets one exporter handle every message type. Byte
// arrays become JSON binary values. Hostile length fields are refused before anything is allocated.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "bricklayer/inspect/lcm_schema.h"

namespace bricklayer::inspect {

using Json = nlohmann::ordered_json;

class DecodeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The message's fingerprint (its first 8 bytes, big-endian); throws DecodeError when shorter.
int64_t message_fingerprint(const void* data, size_t size);

// Decodes a whole message (fingerprint first) of type `type`. Throws DecodeError with the member path
// when the fingerprint differs, the data ends early, a length is negative or larger than the data
// left, a string lacks its terminating NUL, or bytes are left over.
Json decode_message(const LcmTypeSet& types, const LcmStruct& type, const void* data, size_t size);

}  // namespace bricklayer::inspect
