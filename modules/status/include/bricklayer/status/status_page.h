// The status page itself: one self-contained HTML document (no external scripts, styles or fonts: the
// exhibit's network may have no internet) that polls /state.json every second and draws it.
#pragma once

#include <string>

namespace bricklayer::status {

const std::string& status_page_html();

}  // namespace bricklayer::status
