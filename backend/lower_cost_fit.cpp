#include "jpcr/backend/lower_cost_fit.hpp"

#include <optional>
#include <stdexcept>
#include <string>

#include "jpcr/backend/gathered_frame_terms.hpp"
#include "jpcr/quadric/parallel_guard.hpp"

namespace jpcr {

int keep_lower_cost_fits(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                         const std::vector<Eigen::Isometry3d>& poses, const JointParams& params,
                         const QuadricMap& initial, QuadricMap& refined) {
  if (vertices.empty() || poses.size() != vertices.size())
    throw std::invalid_argument("keep_lower_cost_fits: " + std::to_string(poses.size()) +
                                " poses for " + std::to_string(vertices.size()) + " frames");
  const int width = refined.width(), height = refined.height();
  if (initial.width() != width || initial.height() != height)
    throw std::invalid_argument(
        "keep_lower_cost_fits: the initial and refined maps differ in size");
  if (camera.width != width || camera.height != height)
    throw std::invalid_argument("keep_lower_cost_fits: the camera differs in size from the maps");
  for (const VertexMap& f : vertices)
    if (f.width() != width || f.height() != height)
      throw std::invalid_argument("keep_lower_cost_fits: a frame differs in size from the maps");
  const JointTermParams terms = params.terms(true);
  const NeighbourhoodPattern pattern = params.quadric.pattern_for(width);
  const int pattern_size = static_cast<int>(pattern.size());
  const PinholeProjection projection{camera.fx, camera.fy, camera.cx, camera.cy};
  const int frames = static_cast<int>(vertices.size());
  std::vector<VertexView> views;
  std::vector<RigidMotion<double>> motions(vertices.size());
  for (int j = 0; j < frames; ++j) {
    const VertexMap& f = vertices[static_cast<std::size_t>(j)];
    views.push_back(VertexView{f.data(), f.width(), f.height()});
    if (j == 0) continue;  // frame 1 is the reference: the identity, as in the joint terms
    motions[static_cast<std::size_t>(j)].R = poses[static_cast<std::size_t>(j)].linear();
    motions[static_cast<std::size_t>(j)].t = poses[static_cast<std::size_t>(j)].translation();
  }
  int restored = 0;
  const auto restore = [&initial, &refined](int u, int v) {
    refined.set(u, v, initial.quadrics(u, v), initial.curvature(u, v), initial.direction(u, v));
  };
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel reduction(+ : restored)
  {
    std::optional<GatheredFrameTerms<float>> buffers;
    guard.run([&] { buffers.emplace(pattern_size); });
#pragma omp for schedule(dynamic, 8)
    for (int v = 0; v < height; ++v)
      guard.run([&] {
        if (!buffers) return;
        GatheredFrameTerms<float>& gathered = *buffers;
        for (int u = 0; u < width; ++u) {
          if (!initial.valid(u, v)) continue;
          if (!refined.valid(u, v)) {
            // The other half of Quad IT's step test: a step that leaves fewer than min_samples
            // inliers of frame 1 is undone (refined_map marks such a fit kTooFewSamples; its
            // quadric is cleared, so there is no centre to compare).
            if (refined.status(u, v) == QuadricStatus::kTooFewSamples) {
              restore(u, v);
              ++restored;
            }
            continue;
          }
          const Quadricd start = initial.quadrics(u, v).cast<double>();
          const Quadricd fit = refined.quadrics(u, v).cast<double>();
          // The centre p̄ is the pixel's vertex in both (the joint step moves R, t_z, a, b, c, not
          // p̄), so both fits see the same samples, gathered about p̄; the gate and n₀ grow with its
          // range. Maps of other origins, whose centres differ, are not compared.
          if (start.center != fit.center) continue;
          // A quadric the loop left out or never moved (edge_tilt, no other frame saw it) keeps its
          // start to the bit: nothing to compare.
          if (start.R == fit.R && start.t_z == fit.t_z && start.a == fit.a && start.b == fit.b &&
              start.c == fit.c)
            continue;
          const SampleGate<double> limits = SampleGate<double>::at(terms.fit, fit.center);
          double start_cost = 0.0, fit_cost = 0.0;
          for (int j = 0; j < frames; ++j) {
            int su = u, sv = v;
            if (j > 0 && !associate(fit.center, motions[static_cast<std::size_t>(j)],
                                    views[static_cast<std::size_t>(j)], projection, terms, su, sv))
              continue;
            gathered.gather(views[static_cast<std::size_t>(j)],
                            motions[static_cast<std::size_t>(j)], pattern.offsets.data(),
                            pattern_size, su, sv, fit.center);
            int count = 0;
            start_cost += gathered.cost(start, limits, count);
            fit_cost += gathered.cost(fit, limits, count);
          }
          if (start_cost < fit_cost) {
            restore(u, v);
            ++restored;
          }
        }
      });
  }
  guard.rethrow();
  return restored;
}

}  // namespace jpcr
