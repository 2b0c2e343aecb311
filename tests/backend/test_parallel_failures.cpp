// An allocation that fails on an OpenMP worker thread, inside the real parallel regions
// (quadric/parallel_guard.hpp): Quad IT, the sd, keep_lower_cost_fits and the J-ftf, J-full and
// Q-full refiners throw std::bad_alloc to their caller instead of ending the process, and do
// not hang. This program replaces the global operator new so that the N-th allocation on a
// thread other than the caller's fails (not under a sanitizer, which brings its own).
#include <gtest/gtest.h>

#include <omp.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <new>
#include <thread>

#include "joint_test_windows.hpp"
#include "jpcr/backend/fixed_quadric_alignment.hpp"
#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_window.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/quadric/curvature_spread.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define JPCR_OWN_OPERATOR_NEW 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define JPCR_OWN_OPERATOR_NEW 0
#endif
#endif
#ifndef JPCR_OWN_OPERATOR_NEW
#define JPCR_OWN_OPERATOR_NEW 1
#endif

namespace {

std::atomic<long> worker_allocations_left{-1};  // before one fails; negative: none fails
std::thread::id caller;

void arm(long n) {
  caller = std::this_thread::get_id();
  worker_allocations_left.store(n);
}

void disarm() {
  worker_allocations_left.store(-1);
}

}  // namespace

#if JPCR_OWN_OPERATOR_NEW
void* operator new(std::size_t size) {
  if (worker_allocations_left.load(std::memory_order_relaxed) >= 0 &&
      std::this_thread::get_id() != caller && worker_allocations_left.fetch_sub(1) == 0)
    throw std::bad_alloc();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#endif

namespace jpcr {
namespace {

// Runs `work` with the n-th worker allocation failing, for several n: it either throws
// std::bad_alloc or finishes (fewer worker allocations than n), and the first (n = 0) fails.
void expect_failures_reach_the_caller(const char* what, const std::function<void()>& work) {
  int thrown = 0, finished = 0;
  for (const long n : {0L, 1L, 2L, 5L, 20L, 100L, 1000L, 100000L}) {
    arm(n);
    try {
      work();
      ++finished;
    } catch (const std::bad_alloc&) {
      ++thrown;
      if (n == 0) {
        EXPECT_EQ(thrown, 1) << what;
      }
    }
    disarm();
  }
  std::printf("%s: %d runs threw std::bad_alloc, %d finished\n", what, thrown, finished);
  EXPECT_GE(thrown, 1) << what << ": the first worker allocation did not fail";
}

class ParallelFailures : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!JPCR_OWN_OPERATOR_NEW) GTEST_SKIP() << "a sanitizer build brings its own operator new";
    threads_ = omp_get_max_threads();
    omp_set_num_threads(2);  // a worker thread, whatever the machine
  }
  void TearDown() override {
    if (threads_ > 0) omp_set_num_threads(threads_);
  }
  int threads_ = 0;
};

TEST_F(ParallelFailures, QuadItTheSdAndTheLowerCostPassThrowToTheCaller) {
  const test::JointTestWindow w = test::render_window(2, 160, "range:1");
  const JointParams params;
  const QuadricFit fit(params.quadric);
  expect_failures_reach_the_caller("Quad IT", [&] { fit.estimate(w.vertices[0]); });
  const QuadricMap map = fit.estimate(w.vertices[0]);
  const Image<float> sd_reference =
      curvature_spread(map, w.vertices[0], params.quadric.pattern_for(160), params.quadric.fit);
  expect_failures_reach_the_caller("curvature_spread", [&] {
    const Image<float> sd =
        curvature_spread(map, w.vertices[0], params.quadric.pattern_for(160), params.quadric.fit);
    for (std::size_t i = 0; i < sd.size(); ++i)  // a finished run is the run
      ASSERT_TRUE(sd[i] == sd_reference[i] || (std::isnan(sd[i]) && std::isnan(sd_reference[i])));
  });
  QuadricMap bent = map;  // every 7th fit bent: the pass compares those with their start
  for (int v = 0; v < bent.height(); ++v)
    for (int u = (v * 3) % 7; u < bent.width(); u += 7)
      if (bent.valid(u, v)) {
        Quadric q = bent.quadrics(u, v);
        q.a += 20.0f;
        bent.set(u, v, q);
      }
  expect_failures_reach_the_caller("keep_lower_cost_fits", [&] {
    QuadricMap refined = bent;
    keep_lower_cost_fits(w.vertices, w.camera, w.truth, params, map, refined);
  });
}

TEST_F(ParallelFailures, TheJointRefinersThrowToTheCaller) {
  const test::JointTestWindow w = test::render_window(3, 160, "range:1");
  const JointParams params;
  const QuadricMap initial = QuadricFit(params.quadric).estimate(w.vertices[0]);
  std::vector<Eigen::Isometry3d> start = w.truth;
  for (std::size_t j = 1; j < start.size(); ++j)
    start[j] = test::perturbed(w.truth[j], 0.005, 0.2, static_cast<int>(j));
  const std::vector<VertexMap> pair(w.vertices.begin(), w.vertices.begin() + 2);
  const std::vector<Eigen::Isometry3d> pair_start(start.begin(), start.begin() + 2);
  expect_failures_reach_the_caller(
      "J-ftf", [&] { JointFrameToFrame(params).refine(pair, w.camera, pair_start, initial); });
  expect_failures_reach_the_caller(
      "J-full", [&] { JointWindow(params).refine(w.vertices, w.camera, start, initial); });
  expect_failures_reach_the_caller("Q-full", [&] {
    FixedQuadricAlignment(params).refine(w.vertices, w.camera, start, initial);
  });
}

}  // namespace
}  // namespace jpcr
