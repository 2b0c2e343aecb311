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

TEST(DeviceSelection, TheFactoryBuildsTheEstimatorOfTheChosenDevice) {
  std::ostringstream log;
  const auto cpu = make_curvature_estimator(ComputeDevice::kCpu, QuadricParams{}, log);
  EXPECT_EQ(cpu->name(), "quad-it");
  const auto any = make_curvature_estimator(ComputeDevice::kAuto, QuadricParams{}, log);
  EXPECT_EQ(any->name(), cuda_device_available() ? "quad-it-cuda" : "quad-it");
  EXPECT_EQ(lines(log.str()), 2);
}

TEST(DeviceSelection, JFtfRunsOnTheChosenDeviceTheOtherRefinersOnTheCpu) {
  std::ostringstream log;
  const auto cpu = make_refiner("j-ftf", JointParams{}, ComputeDevice::kCpu, log);
  EXPECT_NE(dynamic_cast<const JointFrameToFrame*>(cpu.get()), nullptr);
  EXPECT_EQ(log.str(), "jpcr: device cpu -> cpu (requested)\n");
  log.str("");
  const auto any = make_refiner("j-ftf", JointParams{}, ComputeDevice::kAuto, log);
  EXPECT_EQ(any->name(), "j-ftf");
  EXPECT_EQ(dynamic_cast<const JointFrameToFrame*>(any.get()) == nullptr, cuda_device_available());
  EXPECT_EQ(lines(log.str()), 1) << log.str();
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
