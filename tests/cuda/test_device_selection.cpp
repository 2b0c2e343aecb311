// `device: auto | cpu | cuda` (issue 7): parsing, one log line saying which device was chosen,
// a clear error for cuda without a GPU, and the estimator and refiner the factories build. Runs
// with and without a GPU; each test checks the branch the machine takes.
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_window.hpp"
#include "jpcr/cuda/cpu_fallback_estimator.hpp"
#include "jpcr/cuda/cpu_fallback_refiner.hpp"
#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/curvature_estimator_factory.hpp"
#include "jpcr/cuda/refiner_factory.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {
namespace {

int lines(const std::string& s) {
  int n = 0;
  for (char c : s)
    n += c == '\n' ? 1 : 0;
  return n;
}

TEST(DeviceSelection, ParsesTheThreeNames) {
  EXPECT_EQ(parse_compute_device("auto"), ComputeDevice::kAuto);
  EXPECT_EQ(parse_compute_device("cpu"), ComputeDevice::kCpu);
  EXPECT_EQ(parse_compute_device("cuda"), ComputeDevice::kCuda);
  for (ComputeDevice d : {ComputeDevice::kAuto, ComputeDevice::kCpu, ComputeDevice::kCuda})
    EXPECT_EQ(parse_compute_device(to_string(d)), d);
}

TEST(DeviceSelection, RejectsOtherNamesListingTheAllowedOnes) {
  for (const char* bad : {"gpu0", "", "CUDA", "gpu"}) {
    try {
      parse_compute_device(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(std::string("'") + bad + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("auto, cpu, cuda"), std::string::npos) << what;
    }
  }
}

TEST(DeviceSelection, CpuIsAlwaysTheCpu) {
  std::ostringstream log;
  EXPECT_EQ(resolve_device(ComputeDevice::kCpu, log), ComputeDevice::kCpu);
  EXPECT_EQ(log.str(), "jpcr: device cpu -> cpu (requested)\n");
}

TEST(DeviceSelection, AutoTakesTheGpuWhenThereIsOneAndSaysWhichInOneLine) {
  std::ostringstream log;
  const ComputeDevice chosen = resolve_device(ComputeDevice::kAuto, log);
  EXPECT_EQ(lines(log.str()), 1) << log.str();
  if (cuda_device_available()) {
    EXPECT_EQ(chosen, ComputeDevice::kCuda);
    EXPECT_EQ(log.str().rfind("jpcr: device auto -> cuda (", 0), 0u) << log.str();
    EXPECT_NE(log.str().find(", sm_"), std::string::npos) << log.str();
  } else {
    EXPECT_EQ(chosen, ComputeDevice::kCpu);
    EXPECT_EQ(log.str(), "jpcr: device auto -> cpu (no CUDA device: " +
                             query_cuda_device().description + ")\n");
  }
}

// A GPU object that cannot be built (context or stream creation failed): auto falls back to the
// CPU with one line, an explicit cuda request keeps the error.
TEST(DeviceSelection, AutoFallsBackWhenTheGpuObjectCannotBeBuilt) {
  std::ostringstream log;
  const CudaError failure("jpcr: CUDA call cudaStreamCreate failed: cudaErrorDevicesUnavailable");
  try {
    throw failure;
  } catch (const CudaError& e) {
    EXPECT_NO_THROW(fall_back_to_cpu_or_rethrow(ComputeDevice::kAuto, e, log));
  }
  EXPECT_EQ(log.str(), std::string("jpcr: device auto -> cpu (") + failure.what() + ")\n");
  for (const ComputeDevice requested : {ComputeDevice::kCuda, ComputeDevice::kCpu}) {
    try {
      try {
        throw failure;
      } catch (const CudaError& e) {
        fall_back_to_cpu_or_rethrow(requested, e, log);
      }
      ADD_FAILURE() << "device " << to_string(requested) << " swallowed the error";
    } catch (const CudaError& e) {
      EXPECT_STREQ(e.what(), failure.what());
    }
  }
}

// A test double for a refiner: throws `Failure` from refine when told to, else returns a result
// whose method names it; counts its calls.
template <typename Failure>
class ScriptedRefiner final : public Refiner {
 public:
  ScriptedRefiner(std::string label, bool fails, int* calls)
      : label_(std::move(label)), fails_(fails), calls_(calls) {}
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>&, const CameraIntrinsics&,
                          const std::vector<Eigen::Isometry3d>&, const QuadricMap&) const override {
    ++*calls_;
    if (fails_) throw Failure("scripted device failure");
    RefinementResult r;
    r.report.method = label_;
    return r;
  }
  std::string name() const override { return "j-ftf"; }
  const JointParams& params() const override { return params_; }

 private:
  std::string label_;
  bool fails_;
  int* calls_;
  JointParams params_;
};

// A device failure mid-run: that refinement and every later one run on the CPU, said once; the
// GPU is not tried again. Bad input is not a device failure and passes through.
TEST(CpuFallbackRefiner, ADeviceFailureMovesTheRefinementsToTheCpu) {
  std::ostringstream log;
  int gpu_calls = 0, cpu_calls = 0;
  const CpuFallbackRefiner refiner(
      std::make_unique<ScriptedRefiner<CudaError>>("gpu", true, &gpu_calls),
      std::make_unique<ScriptedRefiner<CudaError>>("cpu", false, &cpu_calls), log);
  EXPECT_FALSE(refiner.on_cpu());
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(refiner.refine(std::vector<VertexMap>{}, CameraIntrinsics{}, {}, QuadricMap{})
                  .report.method,
              "cpu");
  EXPECT_TRUE(refiner.on_cpu());
  EXPECT_EQ(gpu_calls, 1);
  EXPECT_EQ(cpu_calls, 3);
  EXPECT_EQ(lines(log.str()), 1) << log.str();
  EXPECT_NE(log.str().find("j-ftf on the GPU failed (scripted device failure); it runs on the cpu"),
            std::string::npos)
      << log.str();

  int bad_calls = 0, unused = 0;
  const CpuFallbackRefiner strict(
      std::make_unique<ScriptedRefiner<std::invalid_argument>>("gpu", true, &bad_calls),
      std::make_unique<ScriptedRefiner<std::invalid_argument>>("cpu", false, &unused), log);
  EXPECT_THROW(strict.refine(std::vector<VertexMap>{}, CameraIntrinsics{}, {}, QuadricMap{}),
               std::invalid_argument);
  EXPECT_FALSE(strict.on_cpu());
  EXPECT_EQ(unused, 0);
}

// What a scripted device does on each call, in order; calls past the script succeed.
enum class Outcome { kOk, kOutOfMemory, kFault };

void play(const std::vector<Outcome>& script, int call) {
  const Outcome o = call < static_cast<int>(script.size()) ? script[call] : Outcome::kOk;
  if (o == Outcome::kOutOfMemory)
    throw CudaError("cudaMalloc: cudaErrorMemoryAllocation", /*out_of_memory=*/true);
  if (o == Outcome::kFault) throw CudaError("kernel: cudaErrorIllegalAddress");
}

class SequencedRefiner final : public Refiner {
 public:
  SequencedRefiner(std::string label, std::vector<Outcome> script)
      : label_(std::move(label)), script_(std::move(script)) {}
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>&, const CameraIntrinsics&,
                          const std::vector<Eigen::Isometry3d>&, const QuadricMap&) const override {
    play(script_, calls++);
    RefinementResult r;
    r.report.method = label_;
    return r;
  }
  std::string name() const override { return "j-ftf"; }
  const JointParams& params() const override { return params_; }
  mutable int calls = 0;

 private:
  std::string label_;
  std::vector<Outcome> script_;
  JointParams params_;
};

std::vector<std::string> refine_times(const Refiner& refiner, int n) {
  std::vector<std::string> ran;
  for (int i = 0; i < n; ++i)
    ran.push_back(refiner.refine(std::vector<VertexMap>{}, CameraIntrinsics{}, {}, QuadricMap{})
                      .report.method);
  return ran;
}

// Out of device memory is not sticky: only that refinement runs on the CPU, the next one tries
// the GPU again; said once.
TEST(CpuFallbackRefiner, OutOfMemoryMovesOnlyThatRefinementToTheCpu) {
  std::ostringstream log;
  auto gpu = std::make_unique<SequencedRefiner>(
      "gpu", std::vector<Outcome>{Outcome::kOutOfMemory, Outcome::kOk, Outcome::kOutOfMemory});
  const SequencedRefiner& device = *gpu;
  const CpuFallbackRefiner refiner(
      std::move(gpu), std::make_unique<SequencedRefiner>("cpu", std::vector<Outcome>{}), log);
  EXPECT_EQ(refine_times(refiner, 4), (std::vector<std::string>{"cpu", "gpu", "cpu", "gpu"}));
  EXPECT_EQ(device.calls, 4);
  EXPECT_FALSE(refiner.on_cpu());
  EXPECT_EQ(refiner.out_of_memory_calls(), 2);
  EXPECT_EQ(lines(log.str()), 1) << log.str();
  EXPECT_NE(log.str().find("j-ftf on the GPU ran out of device memory (cudaMalloc: "
                           "cudaErrorMemoryAllocation); this call runs on the cpu and the next "
                           "tries the GPU again"),
            std::string::npos)
      << log.str();
}

// A device that stays out of memory is given up after kMaxOutOfMemoryInARow failures in a row,
// with a second line; a success in between resets the count.
TEST(CpuFallbackRefiner, OutOfMemoryInARowMovesTheRefinementsToTheCpuForGood) {
  std::ostringstream log;
  const auto oom = Outcome::kOutOfMemory;
  auto gpu = std::make_unique<SequencedRefiner>(
      "gpu", std::vector<Outcome>{oom, oom, Outcome::kOk, oom, oom, oom, Outcome::kOk});
  const SequencedRefiner& device = *gpu;
  const CpuFallbackRefiner refiner(
      std::move(gpu), std::make_unique<SequencedRefiner>("cpu", std::vector<Outcome>{}), log);
  static_assert(CpuFallback::kMaxOutOfMemoryInARow == 3, "the script assumes 3");
  EXPECT_EQ(refine_times(refiner, 8),
            (std::vector<std::string>{"cpu", "cpu", "gpu", "cpu", "cpu", "cpu", "cpu", "cpu"}));
  EXPECT_EQ(device.calls, 6);
  EXPECT_TRUE(refiner.on_cpu());
  EXPECT_EQ(refiner.out_of_memory_calls(), 5);
  EXPECT_EQ(lines(log.str()), 2) << log.str();
  EXPECT_NE(log.str().find("j-ftf on the GPU ran out of device memory 3 times in a row; it runs "
                           "on the cpu from here on"),
            std::string::npos)
      << log.str();
}

class SequencedEstimator final : public CurvatureEstimator {
 public:
  SequencedEstimator(std::string label, std::vector<Outcome> script)
      : label_(std::move(label)), script_(std::move(script)) {}
  QuadricMap estimate(const VertexMap&) const override {
    play(script_, calls++);
    ran.push_back(label_ + " without normals");
    return QuadricMap{};
  }
  QuadricMap estimate(const VertexMap&, const NormalMap&) const override {
    play(script_, calls++);
    ran.push_back(label_ + " with normals");
    return QuadricMap{};
  }
  std::string name() const override { return label_; }
  const QuadricParams& params() const override { return params_; }
  mutable int calls = 0;
  mutable std::vector<std::string> ran;

 private:
  std::string label_;
  std::vector<Outcome> script_;
  QuadricParams params_;
};

// The GPU Quad IT mid-run: out of memory sends one frame to the CPU, a fault every later one;
// both overloads go the same way, to the same overload on the CPU.
TEST(CpuFallbackEstimator, ADeviceFailureMidRunMovesFramesToTheCpu) {
  std::ostringstream log;
  auto gpu = std::make_unique<SequencedEstimator>(
      "quad-it-cuda",
      std::vector<Outcome>{Outcome::kOutOfMemory, Outcome::kOk, Outcome::kFault, Outcome::kOk});
  auto cpu = std::make_unique<SequencedEstimator>("quad-it", std::vector<Outcome>{});
  const SequencedEstimator& device = *gpu;
  const SequencedEstimator& host = *cpu;
  const CpuFallbackEstimator estimator(std::move(gpu), std::move(cpu), log);
  EXPECT_EQ(estimator.name(), "quad-it-cuda");
  EXPECT_EQ(estimator.cpu_name(), "quad-it");
  const VertexMap vertices;
  const NormalMap normals;
  estimator.estimate(vertices);
  EXPECT_EQ(estimator.cpu_calls(), 1);  // what made the frame, for jpcr_curvature's summary
  estimator.estimate(vertices, normals);
  EXPECT_EQ(estimator.cpu_calls(), 1);
  EXPECT_FALSE(estimator.on_cpu());
  estimator.estimate(vertices, normals);
  EXPECT_TRUE(estimator.on_cpu());
  estimator.estimate(vertices);
  EXPECT_EQ(estimator.cpu_calls(), 3);
  EXPECT_EQ(device.calls, 3);
  EXPECT_EQ(device.ran, (std::vector<std::string>{"quad-it-cuda with normals"}));
  EXPECT_EQ(host.ran, (std::vector<std::string>{"quad-it without normals", "quad-it with normals",
                                                "quad-it without normals"}));
  EXPECT_EQ(estimator.out_of_memory_calls(), 1);
  EXPECT_EQ(lines(log.str()), 2) << log.str();
  EXPECT_NE(log.str().find("quad-it on the GPU ran out of device memory"), std::string::npos)
      << log.str();
  EXPECT_NE(log.str().find("quad-it on the GPU failed (kernel: cudaErrorIllegalAddress); it runs "
                           "on the cpu from here on"),
            std::string::npos)
      << log.str();
}

TEST(DeviceSelection, CudaWithoutAGpuIsAClearError) {
  std::ostringstream log;
  if (cuda_device_available()) {
    EXPECT_EQ(resolve_device(ComputeDevice::kCuda, log), ComputeDevice::kCuda);
    EXPECT_EQ(lines(log.str()), 1);
    return;
  }
  try {
    resolve_device(ComputeDevice::kCuda, log);
    ADD_FAILURE() << "device cuda resolved without a GPU";
  } catch (const CudaError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("device cuda was requested but no CUDA device is usable"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find(query_cuda_device().description), std::string::npos) << what;
    EXPECT_NE(what.find("use device: auto or cpu"), std::string::npos) << what;
  }
  EXPECT_TRUE(log.str().empty());
}

// Whether `auto` found a visible GPU unusable when it built the GPU object (exclusive mode held
// by another process, a MIG slice it may not use): it then says so and takes the CPU.
bool auto_fell_back(const std::string& log) {
  return log.find("jpcr: device auto -> cpu (jpcr: CUDA") != std::string::npos;
}

TEST(DeviceSelection, TheFactoryBuildsTheEstimatorOfTheChosenDevice) {
  std::ostringstream log;
  const auto cpu = make_curvature_estimator(ComputeDevice::kCpu, QuadricParams{}, log);
  EXPECT_EQ(cpu->name(), "quad-it");
  const auto any = make_curvature_estimator(ComputeDevice::kAuto, QuadricParams{}, log);
  const bool gpu = cuda_device_available() && !auto_fell_back(log.str());
  EXPECT_EQ(any->name(), gpu ? "quad-it-cuda" : "quad-it") << log.str();
  EXPECT_EQ(lines(log.str()), auto_fell_back(log.str()) ? 3 : 2) << log.str();
}

TEST(DeviceSelection, JFtfRunsOnTheChosenDeviceTheOtherRefinersOnTheCpu) {
  std::ostringstream log;
  const auto cpu = make_refiner("j-ftf", JointParams{}, ComputeDevice::kCpu, log);
  EXPECT_NE(dynamic_cast<const JointFrameToFrame*>(cpu.get()), nullptr);
  EXPECT_EQ(log.str(), "jpcr: device cpu -> cpu (requested)\n");
  log.str("");
  const auto any = make_refiner("j-ftf", JointParams{}, ComputeDevice::kAuto, log);
  EXPECT_EQ(any->name(), "j-ftf");
  const bool gpu = cuda_device_available() && !auto_fell_back(log.str());
  EXPECT_EQ(dynamic_cast<const JointFrameToFrame*>(any.get()) == nullptr, gpu) << log.str();
  EXPECT_EQ(lines(log.str()), auto_fell_back(log.str()) ? 2 : 1) << log.str();
  log.str("");
  const auto window = make_refiner("j-full", JointParams{}, ComputeDevice::kCuda, log);
  EXPECT_NE(dynamic_cast<const JointWindow*>(window.get()), nullptr);
  EXPECT_EQ(log.str(), "jpcr: j-full has no GPU version; device cuda -> cpu\n");
  EXPECT_THROW(make_refiner("icp", JointParams{}, ComputeDevice::kAuto, log), InputError);
  if (!cuda_device_available()) {
    EXPECT_THROW(make_refiner("j-ftf", JointParams{}, ComputeDevice::kCuda, log), CudaError);
  }
}

TEST(DeviceSelection, TheParameterFileSetsTheDevice) {
  EXPECT_EQ(parse_params("dataset: {}\n", "p.yaml").device, ComputeDevice::kAuto);
  EXPECT_EQ(parse_params("device: cpu\n", "p.yaml").device, ComputeDevice::kCpu);
  EXPECT_EQ(parse_params("device: cuda\n", "p.yaml").device, ComputeDevice::kCuda);
  EXPECT_EQ(load_params(JPCR_SOURCE_DIR "/configs/default.yaml").device, ComputeDevice::kAuto);
  try {
    parse_params("device: gpu0\n", "p.yaml");
    ADD_FAILURE() << "accepted device: gpu0";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("p.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("auto | cpu | cuda"), std::string::npos) << what;
    EXPECT_NE(what.find("'gpu0'"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace jpcr
