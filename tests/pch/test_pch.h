// Precompiled for every test executable (VPM_PCH; tests/CMakeLists.txt):
// the third-party headers most tests reach through vpm's own, parsed once
// per build instead of once per unity batch. Nothing of vpm's here, so a
// change to vpm's headers never rebuilds this one.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <glm/glm.hpp>
#include <vulkan/vulkan.hpp>

#include "vpm/v3/vpm.grpc.pb.h"
