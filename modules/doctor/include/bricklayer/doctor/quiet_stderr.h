// While a check probes a library that prints its own complaints to stderr (libasound's "cannot find
// card '0'", LCM's ten lines about multicast routes), stderr is closed: the check's one line says
// what went wrong and how to fix it, and the doctor's output stays one line per check.
#pragma once

#include <fcntl.h>
#include <unistd.h>

namespace bricklayer::doctor {

class QuietStderr {
 public:
  QuietStderr() : saved_(dup(2)) {
    const int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (null >= 0) {
      dup2(null, 2);
      close(null);
    }
  }
  ~QuietStderr() {
    if (saved_ >= 0) {
      dup2(saved_, 2);
      close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_;
};

}  // namespace bricklayer::doctor
