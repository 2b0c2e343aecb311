// Degenerate input through the whole pipeline (issue 11), the quick case: a single plane, on
// which the front end must say degenerate on every frame (FrameVerdicts), so no keyframe and no
// refinement follows, and the run ends with finite poses. test_hostile_pipeline.cpp has the
// cases in which the back end refines (minutes under AddressSanitizer, so labelled slow).
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

}  // namespace
}  // namespace jpcr::hostile
