#include <gtest/gtest.h>

#include "jpcr/io/mrpt_pose.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

TEST(MrptPose, RoundTripAndComposition) {
  const Eigen::Isometry3d A = se3_exp((Vector6d() << 0.1, -0.2, 0.3, 0.4, 0.1, -0.7).finished());
  const Eigen::Isometry3d B = se3_exp((Vector6d() << -1, 0.5, 0.2, -0.3, 0.2, 0.1).finished());
  EXPECT_LT((from_mrpt(to_mrpt(A)).matrix() - A.matrix()).norm(), 1e-12);
  // Composition means the same thing on both sides: (A ⊕ B) = A * B.
  const mrpt::poses::CPose3D AB = to_mrpt(A) + to_mrpt(B);
  EXPECT_LT((from_mrpt(AB).matrix() - (A * B).matrix()).norm(), 1e-12);
  EXPECT_NEAR(to_mrpt(A).x(), A.translation().x(), 1e-15);
}

}  // namespace
}  // namespace jpcr
