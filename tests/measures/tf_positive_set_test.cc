// TF > 0 as ranges agrees with TF itself.
#include "server/measures/tf_positive_set.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace vpm {
namespace {

void ExpectAgrees(const TransferFunction& tf) {
  const TfPositiveSet set(tf);
  std::vector<double> probes = {-1e30, 1e30, 0.0};
  for (const TfPoint& p : tf.points()) {
    for (double d : {-1.0, -1e-9, 0.0, 1e-9, 1.0}) probes.push_back(p.value + d);
    // Next doubles, but not subnormals next to 0, where TF's own
    // (v - v0) / (v1 - v0) underflows to 0 (see tf_positive_set.h).
    if (std::abs(p.value) > 1e-300) {
      probes.push_back(std::nextafter(p.value, -INFINITY));
      probes.push_back(std::nextafter(p.value, INFINITY));
    }
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-3000.0, 4000.0);
  for (int n = 0; n < 20000; ++n) probes.push_back(static_cast<float>(u(rng)));
  for (double v : probes)
    EXPECT_EQ(set.Contains(v), tf.Evaluate(v) > 0.0) << tf.ToString() << " at " << v;
}

TEST(TfPositiveSet, AgreesWithTheTransferFunction) {
  ExpectAgrees(TransferFunction::CtSoftTissue());
  EXPECT_EQ(TfPositiveSet(TransferFunction::CtSoftTissue()).ranges().size(), 1u);
  ExpectAgrees(*TransferFunction::Create({{50.0, 0.0}, {60.0, 1.0}}));
  ExpectAgrees(*TransferFunction::Create({{0.0, 1.0}}));
  ExpectAgrees(*TransferFunction::Create({{0.0, 0.0}}));
  // A bump, a spike at one value, a step, and a positive tail below.
  ExpectAgrees(*TransferFunction::Create(
      {{-500, 0.4}, {-400, 0}, {0, 0}, {10, 1}, {20, 0}, {100, 0}, {100, 1}, {200, 1}, {300, 0}}));
  ExpectAgrees(*TransferFunction::Create({{0, 0}, {5, 0.5}, {5, 0}, {9, 0}}));
}

}  // namespace
}  // namespace vpm
