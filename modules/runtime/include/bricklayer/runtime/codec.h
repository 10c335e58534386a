// LCM message <-> bytes, without exceptions for bad bytes.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace bricklayer::runtime {

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

// nullopt when the bytes are not a T (wrong fingerprint, malformed, hostile lengths: the generated
// decoders are hardened against those, see lcmtypes/harden_decoders.cmake).
template <typename T>
std::optional<T> decode(const uint8_t* data, size_t size) {
  T msg{};
  if (msg.decode(data, 0, static_cast<int>(size)) < 0) return std::nullopt;
  return msg;
}

template <typename T>
std::optional<T> decode(const std::vector<uint8_t>& bytes) {
  return decode<T>(bytes.data(), bytes.size());
}

}  // namespace bricklayer::runtime
