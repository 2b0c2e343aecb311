#include "jpcr/io/mrpt_pose.hpp"

namespace jpcr {

mrpt::poses::CPose3D to_mrpt(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d R = pose.linear();
  const Eigen::Vector3d t = pose.translation();
  return mrpt::poses::CPose3D(mrpt::math::CMatrixDouble33(R), mrpt::math::CVectorFixedDouble<3>(t));
}

Eigen::Isometry3d from_mrpt(const mrpt::poses::CPose3D& pose) {
  mrpt::math::CMatrixDouble44 H;
  pose.getHomogeneousMatrix(H);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      out.linear()(r, c) = H(r, c);
    out.translation()(r) = H(r, 3);
  }
  return out;
}

}  // namespace jpcr
