// Degenerate and hostile input through the whole pipeline (issue 11), the quick cases: a single
// plane, a frame with < 1 % valid depth and a frame full of NaN/Inf. Each must give a verdict
// that is not ok on the affected frames (FrameVerdicts: the front end's IcpVerdict and the back
// end's RefinementVerdicts), the frames before it stay trusted (so the flag is the event's, not
// the scene's), the pipeline keeps going to the last frame with finite poses, and tracking
// recovers. test_hostile_motion.cpp has the cases that make the back end work for minutes.
#include "hostile_runs.hpp"

namespace jpcr::hostile {
namespace {

TEST(HostileScenes, SinglePlaneIsNotOk) {
  const PipelineRun r = run(walk("single_plane", 6));
  for (std::size_t i = 1; i < r.verdicts.size(); ++i) {
    expect_flagged(r, i);
    EXPECT_EQ(r.verdicts[i].front_end, IcpVerdict::degenerate) << i;
  }
}

// Frame 4 of an 8-frame walk through room_spheres is spoiled: it and only the frames after it may
// be flagged, it must be (too few points to align), and the last frame is tracked again.
void expect_spoiled_frame_flagged(const std::function<void(Frame&)>& spoil) {
  const std::size_t bad = 4;
  const PipelineRun r = run(walk("room_spheres", 8), [&](std::size_t i, Frame& f) {
    if (i == bad) spoil(f);
  });
  expect_trusted_before(r, bad);
  expect_flagged(r, bad);
  EXPECT_EQ(r.verdicts[bad].front_end, IcpVerdict::too_few_points);
  expect_recovered(r);
}

TEST(HostileScenes, FrameWithUnderOnePercentValidDepthIsNotOk) {
  expect_spoiled_frame_flagged(keep_under_one_percent);
}

TEST(HostileScenes, DepthFullOfNanAndInfIsNotOk) {
  expect_spoiled_frame_flagged(fill_non_finite);
}

}  // namespace
}  // namespace jpcr::hostile
