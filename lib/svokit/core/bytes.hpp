#pragma once
// Little-endian byte packing for svokit's file formats. ByteReader never reads past its span:
// every overrun becomes a Status naming what was being read.

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

static_assert(std::endian::native == std::endian::little,
              "svokit's formats are little-endian and read by memcpy");

class ByteWriter {
 public:
  template <class T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void PutArray(std::span<const T> values) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(values.data());
    bytes_.insert(bytes_.end(), p, p + values.size_bytes());
  }
  /// u32 byte length, then the bytes (no terminator, no padding).
  void PutString(const std::string& s) {
    Put(static_cast<std::uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<std::uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

class ByteReader {
 public:
  ByteReader(std::span<const std::uint8_t> bytes, std::string what)
      : bytes_(bytes), what_(std::move(what)) {}

  template <class T>
  Status Get(T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    SVOKIT_RETURN_IF_ERROR(Need(sizeof(T)));
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return Status::Ok();
  }
  template <class T, class Allocator>
  Status GetArray(std::vector<T, Allocator>& values, std::size_t count) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (count > remaining() / sizeof(T)) return Overrun(count * sizeof(T));
    values.resize(count);
    if (count == 0) return Status::Ok();  // an empty vector's data() may be null: no memcpy
    std::memcpy(values.data(), bytes_.data() + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
    return Status::Ok();
  }
  Status GetString(std::string& s) {
    std::uint32_t n = 0;
    SVOKIT_RETURN_IF_ERROR(Get(n));
    SVOKIT_RETURN_IF_ERROR(Need(n));
    s.assign(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return Status::Ok();
  }
  Status GetBytes(std::vector<std::uint8_t>& out, std::size_t n) { return GetArray(out, n); }

  std::size_t remaining() const { return bytes_.size() - pos_; }
  bool at_end() const { return pos_ == bytes_.size(); }

 private:
  Status Need(std::size_t n) const { return n <= remaining() ? Status::Ok() : Overrun(n); }
  Status Overrun(std::size_t n) const {
    return Status::BadInput("{} is truncated (needs {} more bytes at offset {}, has {})", what_, n,
                            pos_, remaining());
  }

  std::span<const std::uint8_t> bytes_;
  std::string what_;
  std::size_t pos_ = 0;
};

}  // namespace svokit
