// Conversions between jpcr poses (Eigen::Isometry3d, camera-to-world) and MRPT's CPose3D, for
// software built on MRPT.
#pragma once

#include <mrpt/poses/CPose3D.h>
#include <Eigen/Geometry>

namespace jpcr {

mrpt::poses::CPose3D to_mrpt(const Eigen::Isometry3d& pose);
Eigen::Isometry3d from_mrpt(const mrpt::poses::CPose3D& pose);

}  // namespace jpcr
