// A downstream program that only knows the installed jpcr package.
#include <cstdio>

#include <jpcr/quadric/camera.hpp>
#include <jpcr/quadric/se3.hpp>

int main() {
  jpcr::Vector6d xi;
  xi << 0.1, 0.2, 0.3, 0.01, -0.02, 0.03;
  const double err = (jpcr::se3_log(jpcr::se3_exp(xi)) - xi).norm();
  jpcr::CameraIntrinsics camera;
  camera.validate();
  std::printf("consumer: se3 round trip error %.3g, camera %dx%d\n", err, camera.width,
              camera.height);
  return err < 1e-12 ? 0 : 1;
}
