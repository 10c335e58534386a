#include "bricklayer/projection/red_debounce.h"

namespace bricklayer::projection {

bool RedDebounce::update(bool red, int64_t now_ms) {
  if (red) {
    clear_since_.reset();
    if (!red_since_) red_since_ = now_ms;
    if (armed_ && now_ms - *red_since_ >= hold_ms_) {
      armed_ = false;
      return true;
    }
    return false;
  }
  red_since_.reset();
  if (!clear_since_) clear_since_ = now_ms;
  if (!armed_ && now_ms - *clear_since_ >= rearm_ms_) armed_ = true;
  return false;
}

}  // namespace bricklayer::projection
