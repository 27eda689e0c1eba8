// The volume model: a scalar image on a regular grid, with its geometry.
//
// Coordinates (docs/ALGORITHM.md section 0):
//  - index space: continuous, voxel centres at integer indices (i, j, k);
//  - physical voxel space (mm): index * spacing_mm, what the algorithm uses;
//  - world space (mm, LPS): origin_mm + direction * (index * spacing_mm), used
//    only when talking to the outside world (files, clients).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/volume/dicom_origin.h"
#include "server/volume/voxel_values.h"

namespace vpm {

struct VolumeGeometry {
  std::array<int64_t, 3> dims{0, 0, 0};      // voxels (nx, ny, nz)
  glm::dvec3 spacing_mm{1.0, 1.0, 1.0};      // voxel size along i, j, k
  glm::dvec3 origin_mm{0.0, 0.0, 0.0};       // world (LPS) position of voxel (0,0,0)
  glm::dmat3 direction{1.0};                 // column c: world (LPS) unit vector of axis c

  int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
  // Physical voxel space (mm) <-> continuous index.
  glm::dvec3 IndexToPhysical(const glm::dvec3& index) const { return index * spacing_mm; }
  glm::dvec3 PhysicalToIndex(const glm::dvec3& p_mm) const { return p_mm / spacing_mm; }
  // World (LPS, mm) <-> physical voxel space (mm). Exact inverse of each other
  // up to floating point, since direction is orthonormal (checked on creation).
  glm::dvec3 PhysicalToWorld(const glm::dvec3& p_mm) const {
    return origin_mm + direction * p_mm;
  }
  glm::dvec3 WorldToPhysical(const glm::dvec3& w_mm) const {
    return glm::transpose(direction) * (w_mm - origin_mm);
  }
  // Directions and offsets (mm or N): rotated only.
  glm::dvec3 PhysicalVectorToWorld(const glm::dvec3& v) const { return direction * v; }
  glm::dvec3 WorldVectorToPhysical(const glm::dvec3& v) const {
    return glm::transpose(direction) * v;
  }
  // The world (LPS) axis-aligned box around the voxel centres, mm: the
  // least and greatest corner.
  std::array<glm::dvec3, 2> WorldBox() const {
    glm::dvec3 lo(std::numeric_limits<double>::infinity());
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    const glm::dvec3 e = extent_mm();
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 w = PhysicalToWorld(
          glm::dvec3((c & 1) ? e.x : 0.0, (c & 2) ? e.y : 0.0, (c & 4) ? e.z : 0.0));
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
    return {lo, hi};
  }
  // Extent of the image box in physical voxel space: (n - 1) * spacing (mm).
  glm::dvec3 extent_mm() const {
    return glm::dvec3(dims[0] - 1, dims[1] - 1, dims[2] - 1) * spacing_mm;
  }
};

// A named point of interest, in physical voxel space (mm).
struct Landmark {
  std::string name;
  glm::dvec3 position_mm{0.0};
  std::string description;
};

// The default budget of one volume's values in memory: a 512 x 512 x 1,024
// int16 CT (or a 512^3 float volume).
inline constexpr int64_t kDefaultMaxVolumeBytes = int64_t{512} << 20;

// Caps that protect the process from absurd inputs. Readers check them before
// allocating.
struct VolumeLimits {
  // Bytes of the volume's values as held (2 per voxel for int16, 4 for
  // float), on the host and again on the device (`--max-volume-bytes`).
  int64_t max_volume_bytes = kDefaultMaxVolumeBytes;
  int64_t max_bytes = int64_t{4} << 30;  // bytes read or inflated from a source
  // Where readers report how far they have read (the fraction of the file
  // or of the folder's files); not owned, may be null. ReadVolume sets it.
  const ProgressFn* read_progress = nullptr;
  // Empty, or a canonical folder (the server's --data-root, an upload's
  // private folder): every file a reader opens must resolve, through
  // symlinks, inside it (server/io/open_source_file.h).
  std::filesystem::path read_root;
  // Polled by the readers as they read (every 4 MiB read, 1 MiB inflated,
  // 1 Mi voxels converted, every DICOM file): a cancelled
  // load stops within milliseconds with the token's status. Default: never.
  CancelToken cancel;
};

// No budget: for volumes derived from one that passed its own (a warp).
inline VolumeLimits UnboundedVolumeLimits() {
  return {.max_volume_bytes = int64_t{1} << 62, .max_bytes = int64_t{1} << 62};
}

// Checks dims, spacing, direction and the byte budget for values held as
// `encoding` (default int16, the smallest: whether any volume of this
// geometry can fit); the message names what is wrong, the size and the budget.
Status ValidateGeometry(const VolumeGeometry& geometry, const VolumeLimits& limits,
                        VoxelEncoding encoding = VoxelEncoding::kInt16);
// "512x512x900 int16 voxels (471.9 MiB)", for messages.
std::string DescribeVolumeSize(const VolumeGeometry& geometry, VoxelEncoding encoding);

class Volume {
 public:
  // `values` has geometry.voxel_count() floats, x fastest: index i + nx*(j + ny*k).
  static Result<Volume> Create(VolumeGeometry geometry, std::vector<float> values,
                               const VolumeLimits& limits = {});
  // The same with values held as int16 + offset or float (voxel_values.h).
  static Result<Volume> Create(VolumeGeometry geometry, VoxelValues values,
                               const VolumeLimits& limits = {});

  const VolumeGeometry& geometry() const { return geometry_; }
  const std::array<int64_t, 3>& dims() const { return geometry_.dims; }
  const glm::dvec3& spacing_mm() const { return geometry_.spacing_mm; }
  // The values as held; read them with voxels()[n] or voxels().Visit(...).
  const VoxelValues& voxels() const { return values_; }
  VoxelEncoding encoding() const { return values_.encoding(); }
  // Bytes of the values in memory (2 or 4 per voxel).
  int64_t value_bytes() const { return values_.size() * values_.bytes_per_voxel(); }

  int64_t LinearIndex(int64_t i, int64_t j, int64_t k) const {
    return i + geometry_.dims[0] * (j + geometry_.dims[1] * k);
  }
  // I[i,j,k] with indices clamped to the volume (section 0).
  float AtClamped(int64_t i, int64_t j, int64_t k) const;
  float At(int64_t i, int64_t j, int64_t k) const { return values_[LinearIndex(i, j, k)]; }

  // Smallest and largest finite value; computed on creation.
  float min_value() const { return min_value_; }
  float max_value() const { return max_value_; }
  // Count of NaN or infinite voxels found on creation; they were replaced by
  // min_value() (the background), so that no NaN reaches the algorithm
  // (always 0 for int16 values).
  int64_t non_finite_count() const { return non_finite_count_; }

  const std::vector<Landmark>& landmarks() const { return landmarks_; }
  void set_landmarks(std::vector<Landmark> landmarks) { landmarks_ = std::move(landmarks); }
  // Where the volume came from (file path or phantom:NAME), for messages.
  const std::string& source() const { return source_; }
  void set_source(std::string source) { source_ = std::move(source); }
  // What a reader corrected or chose on the way in, one sentence each (e.g.
  // "gantry tilt 18.5 deg: resampled onto an orthogonal grid"), so that
  // `vpm volume info` can say that the grid is not the scanner's.
  const std::vector<std::string>& notes() const { return notes_; }
  void add_note(std::string note) { notes_.push_back(std::move(note)); }
  // Where the series held several stacks at the same positions (echoes,
  // phases, b-values): each stack's label ("EchoNumbers 2"), in order, and
  // which one this volume is (1-based); empty and 0 otherwise.
  const std::vector<std::string>& stacks() const { return stacks_; }
  int stack() const { return stack_; }
  void set_stacks(std::vector<std::string> labels, int chosen) {
    stacks_ = std::move(labels);
    stack_ = chosen;
  }
  // The DICOM series it was read from (null for other sources): what an
  // export into the same study needs.
  const std::shared_ptr<const DicomOrigin>& dicom_origin() const { return dicom_origin_; }
  void set_dicom_origin(std::shared_ptr<const DicomOrigin> origin) {
    dicom_origin_ = std::move(origin);
  }

 private:
  Volume(VolumeGeometry geometry, VoxelValues values);

  VolumeGeometry geometry_;
  VoxelValues values_;
  float min_value_ = 0.0f;
  float max_value_ = 0.0f;
  int64_t non_finite_count_ = 0;
  std::vector<Landmark> landmarks_;
  std::string source_;
  std::vector<std::string> notes_;
  std::vector<std::string> stacks_;
  int stack_ = 0;
  std::shared_ptr<const DicomOrigin> dicom_origin_;
};

}  // namespace vpm
