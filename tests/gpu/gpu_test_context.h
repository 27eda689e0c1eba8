// The GPU context shared by the tests of one binary: created once, with the
// Khronos validation layer enabled wherever it is installed. GpuTest fails a
// test on any validation message it caused; the environment fails the binary
// on messages reported at teardown (leaked handles).
#pragma once

#include <gtest/gtest.h>

#include "server/gpu/gpu_context.h"

namespace vpm::testing {

gpu::GpuContext& TestGpuContext();

class GpuTest : public ::testing::Test {
 protected:
  gpu::GpuContext& context() { return TestGpuContext(); }
  void SetUp() override { context().ClearValidationMessages(); }
  void TearDown() override;
};

}  // namespace vpm::testing
