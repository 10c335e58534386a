#include "bricklayer/inspect/lcm_decoder.h"

#include <cstring>
#include <map>

namespace bricklayer::inspect {

namespace {

class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t left() const { return size_ - pos_; }
  const uint8_t* take(size_t n, const std::string& path) {
    if (n > left())
      throw DecodeError(path + ": data ends " + std::to_string(n - left()) + " byte(s) early (at byte " +
                        std::to_string(pos_) + " of " + std::to_string(size_) + ")");
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  uint64_t big_endian(size_t n, const std::string& path) {
    const uint8_t* p = take(n, path);
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) v = (v << 8) | p[i];
    return v;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

size_t primitive_size(const std::string& t) {
  if (t == "int8_t" || t == "boolean" || t == "byte") return 1;
  if (t == "int16_t") return 2;
  if (t == "int32_t" || t == "float") return 4;
  if (t == "string") return 5;  // length + the terminating NUL
  return 8;                     // int64_t, double
}

class Decoder {
 public:
  explicit Decoder(const LcmTypeSet& types) : types_(types) {}

  Json decode_struct(const LcmStruct& s, Reader& in, const std::string& path) {
    Json out = Json::object();
    for (const auto& m : s.members) {
      std::string p = path + "." + m.name;
      std::vector<int64_t> sizes;
      for (const auto& d : m.dimensions) {
        if (!d.variable) {
          sizes.push_back(d.size);
          continue;
        }
        const Json& n = out.at(d.size_member);
        int64_t count = n.get<int64_t>();
        if (count < 0) throw DecodeError(p + ": length " + d.size_member + " = " + std::to_string(count) + " is negative");
        sizes.push_back(count);
      }
      out[m.name] = decode_array(m, sizes, 0, in, p);
    }
    return out;
  }

 private:
  Json decode_array(const LcmMember& m, const std::vector<int64_t>& sizes, size_t dim, Reader& in, const std::string& path) {
    if (dim == sizes.size()) return decode_value(m.type, in, path);
    int64_t count = sizes[dim];
    // Refuse a length the data cannot hold before allocating anything for it.
    size_t per_element = min_size(m.type);
    for (size_t d = dim + 1; d < sizes.size(); ++d) per_element *= static_cast<size_t>(sizes[d]);
    if (per_element > 0 && static_cast<uint64_t>(count) > in.left() / per_element)
      throw DecodeError(path + ": " + std::to_string(count) + " elements cannot fit in the " +
                        std::to_string(in.left()) + " byte(s) left");
    if (m.type == "byte" && dim + 1 == sizes.size()) {
      const uint8_t* p = in.take(static_cast<size_t>(count), path);
      return Json::binary(std::vector<uint8_t>(p, p + count));
    }
    Json arr = Json::array();
    for (int64_t i = 0; i < count; ++i) arr.push_back(decode_array(m, sizes, dim + 1, in, path + "[" + std::to_string(i) + "]"));
    return arr;
  }

  Json decode_value(const std::string& type, Reader& in, const std::string& path) {
    if (type == "int8_t") return static_cast<int8_t>(in.big_endian(1, path));
    if (type == "byte") return static_cast<uint8_t>(in.big_endian(1, path));
    if (type == "boolean") return in.big_endian(1, path) != 0;
    if (type == "int16_t") return static_cast<int16_t>(in.big_endian(2, path));
    if (type == "int32_t") return static_cast<int32_t>(in.big_endian(4, path));
    if (type == "int64_t") return static_cast<int64_t>(in.big_endian(8, path));
    if (type == "float") {
      uint32_t bits = static_cast<uint32_t>(in.big_endian(4, path));
      float f;
      std::memcpy(&f, &bits, 4);
      return static_cast<double>(f);
    }
    if (type == "double") {
      uint64_t bits = in.big_endian(8, path);
      double d;
      std::memcpy(&d, &bits, 8);
      return d;
    }
    if (type == "string") {
      int32_t length = static_cast<int32_t>(in.big_endian(4, path));
      if (length <= 0) throw DecodeError(path + ": string length " + std::to_string(length) + " (it counts the NUL, so >= 1)");
      const uint8_t* p = in.take(static_cast<size_t>(length), path);
      if (p[length - 1] != 0) throw DecodeError(path + ": string without its terminating NUL");
      return std::string(reinterpret_cast<const char*>(p), static_cast<size_t>(length - 1));
    }
    const LcmStruct* s = types_.find(type);
    if (!s) throw DecodeError(path + ": unknown type " + type);
    return decode_struct(*s, in, path);
  }

  size_t min_size(const std::string& type) {
    if (is_lcm_primitive(type)) return primitive_size(type);
    auto it = min_sizes_.find(type);
    if (it != min_sizes_.end()) return it->second;
    min_sizes_[type] = 0;  // a recursive type counts 0 for itself (no bound from it)
    size_t total = 0;
    for (const auto& m : types_.find(type)->members) {
      size_t n = min_size(m.type);
      for (const auto& d : m.dimensions) n = d.variable ? 0 : n * static_cast<size_t>(d.size);
      total += n;
    }
    return min_sizes_[type] = total;
  }

  const LcmTypeSet& types_;
  std::map<std::string, size_t> min_sizes_;
};

}  // namespace

int64_t message_fingerprint(const void* data, size_t size) {
  Reader in(static_cast<const uint8_t*>(data), size);
  if (size < 8) throw DecodeError("message of " + std::to_string(size) + " byte(s) is shorter than its 8-byte fingerprint");
  return static_cast<int64_t>(in.big_endian(8, "fingerprint"));
}

Json decode_message(const LcmTypeSet& types, const LcmStruct& type, const void* data, size_t size) {
  int64_t fp = message_fingerprint(data, size);
  int64_t want = types.fingerprint(type.full_name());
  if (fp != want) throw DecodeError(type.full_name() + ": fingerprint differs (not this type, or another version of it)");
  Reader in(static_cast<const uint8_t*>(data) + 8, size - 8);
  Decoder decoder(types);
  Json out = decoder.decode_struct(type, in, type.name);
  if (in.left() != 0) throw DecodeError(type.full_name() + ": " + std::to_string(in.left()) + " byte(s) left over after the message");
  return out;
}

}  // namespace bricklayer::inspect
