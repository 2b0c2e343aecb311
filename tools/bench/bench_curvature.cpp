// Speed of the single-frame curvature estimators (issue 4: Quad IT ≤ 150 ms per 640x480 frame
// with the reference 129-sample pattern and 3 iterations, on 2 cores). Each benchmark estimates
// one rendered room_spheres frame with range:1 noise; normals are included (they are part of
// what a caller pays). Arguments: image width (the height is 3/4 of it). At the end it prints
// Quad IT's time as a ratio of the CGAL jet peer's (when built with CGAL) and Quad LS's of
// Quad IT's, from the same run.
#include <benchmark/benchmark.h>

#include <string>

#include "benchmark_main.hpp"

#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/curvature_spread.hpp"
#include "jpcr/quadric/least_squares_quadric.hpp"
#ifdef JPCR_HAVE_CGAL
#include "peers/cgal_jet_curvature.hpp"
#endif

namespace {

jpcr::VertexMap frame(int width) {
  jpcr::SyntheticSequenceOptions options;
  options.frames = 1;
  options.noise = "range:1";
  options.width = width;
  options.height = width * 3 / 4;
  const jpcr::SyntheticSequence seq = jpcr::make_synthetic_sequence(options);
  const jpcr::Frame f = seq.load(0);
  return jpcr::compute_vertex_map(f.depth, f.camera);
}

template <typename Estimator>
void run(benchmark::State& state) {
  const jpcr::VertexMap vertices = frame(static_cast<int>(state.range(0)));
  const Estimator estimator;
  std::size_t valid = 0;
  for (auto _ : state) {
    const jpcr::QuadricMap map = estimator.estimate(vertices);
    valid = map.valid_count();
    benchmark::DoNotOptimize(valid);
  }
  state.counters["valid_px"] = static_cast<double>(valid);
  state.counters["samples"] = estimator.params().pattern.for_width(vertices.width()).size();
  state.SetItemsProcessed(state.iterations());
}

void BM_QuadIT(benchmark::State& state) {
  run<jpcr::QuadricFit>(state);
}
void BM_QuadLS(benchmark::State& state) {
  run<jpcr::LeastSquaresQuadric>(state);
}

#ifdef JPCR_HAVE_CGAL
void BM_CgalJetPeer(benchmark::State& state) {  // CGAL Monge jet fitting, same pattern
  run<jpcr::peers::CgalJetCurvature>(state);
}
BENCHMARK(BM_CgalJetPeer)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();
#endif

// The sd of every pixel of Quad IT's map (curvature_spread.hpp), which jpcr_run and
// jpcr_curvature write beside each map: one more pass over each pixel's samples.
void BM_CurvatureSpread(benchmark::State& state) {
  const jpcr::VertexMap vertices = frame(static_cast<int>(state.range(0)));
  const jpcr::QuadricFit fit;
  const jpcr::QuadricMap map = fit.estimate(vertices);
  const jpcr::NeighbourhoodPattern pattern = fit.params().pattern_for(vertices.width());
  for (auto _ : state)
    benchmark::DoNotOptimize(jpcr::curvature_spread(map, vertices, pattern, fit.params().fit));
}

void BM_Normals(benchmark::State& state) {
  const jpcr::VertexMap vertices = frame(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(jpcr::estimate_normals(vertices));
}

BENCHMARK(BM_QuadIT)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_QuadLS)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CurvatureSpread)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Normals)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  return jpcr::bench::benchmark_main(
      argc, argv, "bench_curvature",
      "Times Quad IT, Quad LS, the curvature sd of Quad IT's map and the initial normals (and\n"
      "the CGAL jet peer where built with CGAL) on one rendered room_spheres frame with 1 %\n"
      "range noise, at 320x240 and 640x480, then prints Quad IT / CGAL jet, Quad LS / Quad IT\n"
      "and the sd / Quad IT from the same run.",
      {{"BM_QuadIT", "BM_CgalJetPeer"},
       {"BM_QuadLS", "BM_QuadIT"},
       {"BM_CurvatureSpread", "BM_QuadIT"}});
}
