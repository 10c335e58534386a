// JSON Schemas (draft-07) of the messages, generated from their .lcm definitions: every member
// required, no others allowed, integer ranges of their LCM type, fixed array sizes, the member's .lcm
// comment (with its unit) and the struct's constants as descriptions. The same JSON form
// mcap_json() produces, so an exported message validates against its schema.
#pragma once

#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/lcm_schema.h"

namespace bricklayer::inspect {

// The type of an image's bytes: in MCAP they travel as a foxglove image on their own topic, so the
// JSON form and its schema leave `data` out.
inline constexpr const char* kImageType = "bricklayer.image_t";

Json json_schema(const LcmTypeSet& types, const LcmStruct& type);

// A decoded message as MCAP's JSON: image bytes dropped, other byte arrays as arrays of integers;
// NaN and infinities become null (JSON has no such numbers; the schema allows null for floats).
Json mcap_json(const LcmTypeSet& types, const LcmStruct& type, const Json& message);

}  // namespace bricklayer::inspect
