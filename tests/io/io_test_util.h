// Helpers shared by the volume I/O tests: temp folders, files, volumes.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm::testing {

// A fresh empty folder under ::testing::TempDir(), unique to the current test
// and process (ctest -j runs tests, and other builds' tests, side by side).
inline std::filesystem::path MakeTempDir() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) /
                              ("vpm_io_" + std::to_string(::getpid())) /
                              (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void WriteBytes(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

template <typename T>
void AppendScalar(std::vector<uint8_t>& out, T value, bool big_endian = false) {
  uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian) {
    for (size_t a = 0, b = sizeof(T) - 1; a < b; ++a, --b) std::swap(bytes[a], bytes[b]);
  }
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

inline std::vector<uint8_t> ToBytes(const std::string& text) {
  return std::vector<uint8_t>(text.begin(), text.end());
}

// `v` failed with `code` and a message containing `fragment`.
inline void ExpectError(const Result<Volume>& v, absl::StatusCode code,
                        const std::string& fragment) {
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), code) << v.status();
  EXPECT_NE(v.status().message().find(fragment), absl::string_view::npos) << v.status();
}

// A rotated, anisotropic, offset geometry: i -> +y, j -> -x, k -> +z (LPS).
inline VolumeGeometry RotatedGeometry(std::array<int64_t, 3> dims) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = {0.5, 1.25, 2.5};
  g.origin_mm = {-10.5, 20.25, 5.0};
  g.direction = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));
  return g;
}

// Values n * 1.5 - 7 for n = 0, 1, ... (distinct, negative and fractional).
inline std::vector<float> RampValues(int64_t count) {
  std::vector<float> values(static_cast<size_t>(count));
  for (int64_t n = 0; n < count; ++n) values[n] = static_cast<float>(n) * 1.5f - 7.0f;
  return values;
}

inline void ExpectGeometryNear(const VolumeGeometry& a, const VolumeGeometry& b, double tol) {
  EXPECT_EQ(a.dims, b.dims);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(a.spacing_mm[c], b.spacing_mm[c], tol) << "spacing " << c;
    EXPECT_NEAR(a.origin_mm[c], b.origin_mm[c], tol) << "origin " << c;
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(a.direction[c][r], b.direction[c][r], tol)
          << "direction col " << c << " row " << r;
    }
  }
}

}  // namespace vpm::testing
