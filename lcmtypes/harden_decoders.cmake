# Hardens one lcm-gen 1.3.1 C++ header against hostile input (found by tests/fuzz/fuzz_lcm_messages):
#  - a negative string length makes decode() call std::string::assign with a huge size (throws);
#  - an array length field is trusted before any bytes are checked, so a 50-byte message claiming
#    10^8 blocks makes decode() allocate and zero gigabytes before failing.
# Every string carries at least its NUL byte and every array element at least one byte, so lengths
# outside [1, remaining] (strings) or [0, remaining] (arrays) are rejected before anything is allocated.
# Usage: cmake -DFILE=path/to/type.hpp -P harden_decoders.cmake
file(READ "${FILE}" text)
string(REGEX REPLACE "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
       "if(\\1 < 1 || \\1 > maxlen - pos) return -1;" text "${text}")
string(REGEX REPLACE "([ ]*)this->([A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
       "\\1if(this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;\n\\1this->\\2.resize(this->\\3);" text "${text}")
file(WRITE "${FILE}" "${text}")
