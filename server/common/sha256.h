// Incremental SHA-256 (OpenSSL's libcrypto EVP interface), for upload checks.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace vpm {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void Update(std::span<const uint8_t> bytes);
  // Lower-case hex of the digest; the object is spent afterwards.
  std::string FinishHex();

  static std::string HexOf(std::span<const uint8_t> bytes);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm
