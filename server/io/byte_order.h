// Loading scalars of a given byte order from unaligned bytes.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace vpm {

enum class Endian { kLittle, kBig };

inline constexpr Endian HostEndian() {
  return std::endian::native == std::endian::big ? Endian::kBig : Endian::kLittle;
}

// Reverses the bytes of `n` bytes at `p` in place.
inline void SwapBytesInPlace(uint8_t* p, size_t n) {
  for (size_t a = 0, b = n - 1; a < b; ++a, --b) {
    const uint8_t t = p[a];
    p[a] = p[b];
    p[b] = t;
  }
}

// The scalar T stored at `p` (no alignment needed) in byte order `endian`.
template <typename T>
T LoadScalar(const uint8_t* p, Endian endian) {
  static_assert(std::is_trivially_copyable_v<T>);
  uint8_t buffer[sizeof(T)];
  std::memcpy(buffer, p, sizeof(T));
  if (endian != HostEndian()) SwapBytesInPlace(buffer, sizeof(T));
  T value;
  std::memcpy(&value, buffer, sizeof(T));
  return value;
}

// Stores `value` at `p` in byte order `endian`.
template <typename T>
void StoreScalar(T value, uint8_t* p, Endian endian) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(p, &value, sizeof(T));
  if (endian != HostEndian()) SwapBytesInPlace(p, sizeof(T));
}

}  // namespace vpm
