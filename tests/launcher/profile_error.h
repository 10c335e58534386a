// The error a profile's text is refused with, for the tests that check what a mistake says.
#pragma once

#include <string>

#include "bricklayer/launcher/profile.h"

namespace bricklayer::test {

// ProfileError's message for json read as the profile named source ("profile p line 3: ..."), or ""
// when it parses.
inline std::string profile_error(const std::string& json, const std::string& source = "p") {
  try {
    launcher::parse_profile(json, source);
  } catch (const launcher::ProfileError& e) {
    return e.what();
  }
  return "";
}

}  // namespace bricklayer::test
