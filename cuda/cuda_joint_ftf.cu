// J-ftf on the GPU: one thread per reference pixel runs the CPU reference's per-pixel code
// (backend/joint_pixel_kernel.hpp) and the reduced 6x6 system is summed in double.
//
//   linearize_pair  linearize_joint_pixel<Scalar, 2> (C_p, B_p, A_p, b_p, a_p, the Cholesky
//                   factor of the damped C_p and k = C_p⁻¹ b_p, K = C_p⁻¹ B_pᵀ, all in the
//                   thread's registers / local memory), add_schur_terms into the thread's 33
//                   Schur numbers (21 of S, 6 of s, 6 of diag A; method.md §6/§7) plus cost,
//                   terms, active and seen; k and K (42 numbers) stored per pixel for the
//                   step. Each block reduces its 37 sums with warp shuffles and shared memory
//                   and writes them to its own slot of `partials`.
//   sum_partials    one block per sum adds the blocks' partials in a fixed order: the reduction
//                   is deterministic (no atomics), run to run equal.
//   step_pair       Δγ_p = k − K Δξ (method.md §7), γ ⊕ Δγ in double, and the candidate's cost
//                   linearized_pixel_cost over the linearisation's terms (frame 2's pattern
//                   where it was associated at the linearised pose; method.md §6); every
//                   pixel's candidate quadric is written (inactive ones keep γ_p).
//
// Scalar is the linearisation's type; the state (γ_p, T₂) and every sum stay double.
#include "jpcr/cuda/cuda_joint_ftf.hpp"

#include <stdexcept>
#include <utility>

#include <cuda_runtime.h>

#include "jpcr/backend/joint_pixel_kernel.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"
#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/device_memory.hpp"
#include "jpcr/cuda/stream_events.hpp"

namespace jpcr {

namespace {

// 32x8 threads as in Quad IT: a warp covers 32 consecutive pixels of a row, so the frame-1
// samples of one pattern offset are one coalesced run and every lane reads the same offset.
constexpr int kBlockWidth = 32;
constexpr int kBlockHeight = 8;
constexpr int kThreads = kBlockWidth * kBlockHeight;
constexpr int kWarps = kThreads / 32;

// The per-thread sums of the linearisation, in this order.
constexpr int kSchurLower = 21;      // S(r, c), c ≤ r, row by row
constexpr int kRhs = kSchurLower;    // s(0..5)
constexpr int kDiagA = kRhs + 6;     // A(r, r)
constexpr int kCost = kDiagA + 6;    // Σ w r²
constexpr int kTerms = kCost + 1;    // terms inside the gate
constexpr int kActive = kTerms + 1;  // active quadrics
constexpr int kSeen = kActive + 1;   // active quadrics frame 2 sees
constexpr int kSums = kSeen + 1;     // 37
constexpr int kFactors = 42;         // k (6), then K column by column (36)

// What every pixel reads: the two frames, their poses T_1 = I and T_2, camera and pattern.
template <typename Scalar>
struct PairInputs {
  VertexView views[2];
  RigidMotion<Scalar> motions[2];
  PinholeProjection camera;
  const PixelOffset* pattern;
  int pattern_size;
  int width, height;

  __device__ JointWindowView<Scalar> window() const {
    return JointWindowView<Scalar>{views, motions, 2, camera, pattern, pattern_size};
  }
};

// Δξ as a kernel parameter: a plain array, so its layout cannot differ between the host and the
// device passes (a 48-byte Eigen vector may be 16-byte aligned on the host only).
template <typename Scalar>
struct PoseStep {
  Scalar xi[6];
};

// Sums x over the block (all threads must call it) and writes the N totals to out (thread t
// writes out[t]). Warp shuffles, then one shared slot per warp, added in warp order.
template <int N>
__device__ void block_sum(double (&x)[N], double* out) {
  __shared__ double warp_sums[kWarps][N];
  const int t = threadIdx.y * blockDim.x + threadIdx.x;
  const int lane = t % 32, warp = t / 32;
#pragma unroll
  for (int k = 0; k < N; ++k) {
    double value = x[k];
#pragma unroll
    for (int offset = 16; offset > 0; offset /= 2)
      value += __shfl_down_sync(0xffffffffu, value, offset);
    if (lane == 0) warp_sums[warp][k] = value;
  }
  __syncthreads();
  for (int k = t; k < N; k += kThreads) {
    double total = 0.0;
    for (int w = 0; w < kWarps; ++w)
      total += warp_sums[w][k];
    out[k] = total;
  }
}

template <typename Scalar>
__global__ void __launch_bounds__(kThreads)
    linearize_pair(const __grid_constant__ PairInputs<Scalar> in,
                   const Quadricd* __restrict__ quadrics, const unsigned char* __restrict__ valid,
                   JointTermParams params, Scalar lambda, Scalar* __restrict__ factors,
                   unsigned char* __restrict__ active, double* __restrict__ partials) {
  const int u = blockIdx.x * kBlockWidth + threadIdx.x;
  const int v = blockIdx.y * kBlockHeight + threadIdx.y;
  double sums[kSums];
#pragma unroll
  for (int k = 0; k < kSums; ++k)
    sums[k] = 0.0;
  if (u < in.width && v < in.height) {
    const int i = v * in.width + u;
    const std::size_t pixels = static_cast<std::size_t>(in.width) * in.height;
    unsigned char is_active = 0;
    if (valid[i]) {
      JointPixelSystem<Scalar, 2> sys;
      linearize_joint_pixel(quadrics[i].template cast<Scalar>(), in.window(), u, v, params, lambda,
                            sys);
      if (sys.active) {
        is_active = 1;
        double S[36] = {}, s[6] = {}, A_diagonal[6] = {};
        add_schur_terms(sys, 2, true, S, s, A_diagonal);
        int n = 0;
#pragma unroll
        for (int r = 0; r < 6; ++r)
#pragma unroll
          for (int c = 0; c <= r; ++c)
            sums[n++] = S[r * 6 + c];
#pragma unroll
        for (int r = 0; r < 6; ++r) {
          sums[kRhs + r] = s[r];
          sums[kDiagA + r] = A_diagonal[r];
        }
        sums[kCost] = double(sys.cost);
        sums[kTerms] = double(sys.count);
        sums[kActive] = 1.0;
        sums[kSeen] = sys.seen[0] ? 1.0 : 0.0;
        // Structure of arrays: factor f of pixel i at f · pixels + i (coalesced per warp).
#pragma unroll
        for (int r = 0; r < 6; ++r)
          factors[r * pixels + i] = sys.k(r);
#pragma unroll
        for (int c = 0; c < 6; ++c)
#pragma unroll
          for (int r = 0; r < 6; ++r)
            factors[(6 + 6 * c + r) * pixels + i] = sys.K[0](r, c);
      }
    }
    active[i] = is_active;
  }
  block_sum(sums, partials + static_cast<std::size_t>(blockIdx.y * gridDim.x + blockIdx.x) * kSums);
}

// totals[b] = Σ_k partials[k · stride + b] over `blocks` partials, one block per b.
__global__ void __launch_bounds__(kThreads)
    sum_partials(const double* __restrict__ partials, int blocks, int stride,
                 double* __restrict__ totals) {
  const int t = threadIdx.y * blockDim.x + threadIdx.x;
  double x[1] = {0.0};
  for (int k = t; k < blocks; k += kThreads)
    x[0] += partials[static_cast<std::size_t>(k) * stride + blockIdx.x];
  block_sum(x, totals + blockIdx.x);
}

template <typename Scalar>
__global__ void __launch_bounds__(kThreads)
    step_pair(const __grid_constant__ PairInputs<Scalar> linearized,
              const __grid_constant__ PairInputs<Scalar> next,
              const Quadricd* __restrict__ quadrics, const unsigned char* __restrict__ active,
              const Scalar* __restrict__ factors, JointTermParams params,
              PoseStep<Scalar> pose_step, Quadricd* __restrict__ candidate,
              double* __restrict__ partials) {
  const int u = blockIdx.x * kBlockWidth + threadIdx.x;
  const int v = blockIdx.y * kBlockHeight + threadIdx.y;
  double cost[1] = {0.0};
  if (u < next.width && v < next.height) {
    const int i = v * next.width + u;
    const std::size_t pixels = static_cast<std::size_t>(next.width) * next.height;
    const Quadricd q_lin = quadrics[i];
    Quadricd q = q_lin;
    if (active[i]) {
      QuadricVector<Scalar> delta;  // Δγ_p = k − K Δξ
#pragma unroll
      for (int r = 0; r < 6; ++r)
        delta(r) = factors[r * pixels + i];
#pragma unroll
      for (int c = 0; c < 6; ++c)
#pragma unroll
        for (int r = 0; r < 6; ++r)
          delta(r) -= factors[(6 + 6 * c + r) * pixels + i] * pose_step.xi[c];
      apply_quadric_update(q, QuadricVector<double>(delta.template cast<double>()));
      cost[0] =
          double(linearized_pixel_cost(q.template cast<Scalar>(), q_lin.template cast<Scalar>(),
                                       linearized.window(), next.window(), u, v, 1u, params));
    }
    candidate[i] = q;
  }
  block_sum(cost, partials + blockIdx.y * gridDim.x + blockIdx.x);
}

template <typename Scalar>
RigidMotion<Scalar> motion_of(const Eigen::Isometry3d& T) {
  RigidMotion<Scalar> m;
  m.R = T.linear().cast<Scalar>();
  m.t = T.translation().cast<Scalar>();
  return m;
}

template <typename T>
void poison(DeviceArray<T>& a, std::size_t count, cudaStream_t stream) {
  JPCR_CUDA_CHECK(cudaMemsetAsync(a.data(), 0xFF, count * sizeof(T), stream));
}

}  // namespace

// The stream, the timing events and the buffers, sized for the largest pair seen so far.
struct CudaJointSystem::Device : StreamEvents<4> {  // linearize start/end, propose start/end
  DeviceArray<Eigen::Vector3f> vertices[2];
  DeviceArray<PixelOffset> pattern;
  DeviceArray<Quadricd> quadrics, candidate;
  DeviceArray<unsigned char> valid, active;
  DeviceArray<double> factors;  // kFactors Scalars per pixel, in doubles (factor_doubles)
  DeviceArray<double> partials, totals;
  double host_totals[kSums] = {};
  std::size_t allocations = 0;
  int width = 0, height = 0, pattern_size = 0;
  PinholeProjection camera;

  std::size_t pixels() const { return static_cast<std::size_t>(width) * height; }
  dim3 grid() const {
    return dim3((width + kBlockWidth - 1) / kBlockWidth,
                (height + kBlockHeight - 1) / kBlockHeight);
  }
  int blocks() const {
    const dim3 g = grid();
    return static_cast<int>(g.x * g.y);
  }

  // The doubles that hold kFactors Scalars per pixel: half as many for float.
  static std::size_t factor_doubles(std::size_t pixels, CudaPrecision precision) {
    const std::size_t scalar = precision == CudaPrecision::kDouble ? sizeof(double) : sizeof(float);
    return (kFactors * pixels * scalar + sizeof(double) - 1) / sizeof(double);
  }

  // One at a time, so that the allocations made before one that throws are counted.
  void reserve(std::size_t pixels, std::size_t pattern_size, int blocks, CudaPrecision precision) {
    allocations += vertices[0].reserve(pixels);
    allocations += vertices[1].reserve(pixels);
    allocations += pattern.reserve(pattern_size);
    allocations += quadrics.reserve(pixels);
    allocations += candidate.reserve(pixels);
    allocations += valid.reserve(pixels);
    allocations += active.reserve(pixels);
    allocations += factors.reserve(factor_doubles(pixels, precision));
    allocations += partials.reserve(static_cast<std::size_t>(blocks) * kSums);
    allocations += totals.reserve(kSums);
  }

  template <typename Scalar>
  PairInputs<Scalar> inputs(const std::vector<Eigen::Isometry3d>& poses) const {
    PairInputs<Scalar> in{};
    for (int j = 0; j < 2; ++j) {
      in.views[j] = VertexView{vertices[j].data(), width, height};
      in.motions[j] = motion_of<Scalar>(poses[static_cast<std::size_t>(j)]);
    }
    in.camera = camera;
    in.pattern = pattern.data();
    in.pattern_size = pattern_size;
    in.width = width;
    in.height = height;
    return in;
  }

  // The block partials of `count` sums to the host (host_totals), synchronously.
  void download_totals(int count) {
    sum_partials<<<count, dim3(kBlockWidth, kBlockHeight), 0, stream>>>(partials.data(), blocks(),
                                                                        count, totals.data());
    JPCR_CUDA_CHECK_LAUNCH("sum_partials", stream);
    JPCR_CUDA_CHECK(cudaMemcpyAsync(host_totals, totals.data(), count * sizeof(double),
                                    cudaMemcpyDeviceToHost, stream));
  }
};

CudaJointSystem::CudaJointSystem(const JointTermParams& params, CudaPrecision precision)
    : params_(params), precision_(precision) {
  if (!params_.estimate_quadrics)
    throw std::invalid_argument("CudaJointSystem: only J-ftf (estimate_quadrics) runs on the GPU");
  device_ = std::make_unique<Device>();
}

CudaJointSystem::~CudaJointSystem() = default;

namespace {

// Throws std::invalid_argument unless two frames of one size (width and height: the kernels read
// frame 2 with frame 1's), two poses and one quadric and one validity flag per pixel: checked
// before load() touches anything, so a rejected pair leaves the loaded one as it was.
void check_pair(const std::vector<VertexMap>& frames, std::size_t poses, std::size_t quadrics,
                std::size_t valid, std::size_t edges = 0) {
  if (frames.size() != 2 || poses != 2)
    throw std::invalid_argument("CudaJointSystem: J-ftf needs exactly two frames and two poses");
  const std::size_t pixels = frames[0].size();
  if (frames[1].width() != frames[0].width() || frames[1].height() != frames[0].height() ||
      quadrics != pixels || valid != pixels || (edges != 0 && edges != pixels))
    throw std::invalid_argument("CudaJointSystem: frames and state differ in size");
}

}  // namespace

void CudaJointSystem::load(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                           const NeighbourhoodPattern& pattern, JointState initial) {
  check_pair(frames, initial.poses.size(), initial.quadrics.size(), initial.valid.size());
  const DeviceScope scope(device_->device);
  state_ = std::move(initial);
  upload(frames, camera, pattern);
}

int CudaJointSystem::load(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                          const NeighbourhoodPattern& pattern,
                          const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& initial,
                          const std::vector<unsigned char>& edges) {
  check_pair(frames, poses.size(), initial.status.size(), initial.status.size(), edges.size());
  if (initial.width() != frames[0].width() || initial.height() != frames[0].height())
    throw std::invalid_argument("CudaJointSystem: the quadric map differs in size from frame 0");
  const DeviceScope scope(device_->device);
  fill_joint_state(poses, initial, state_);
  const int left_out = leave_out(edges, state_);
  upload(frames, camera, pattern);
  return left_out;
}

// A device error part way (out of memory, a lost device) leaves nothing loaded rather than a
// pair whose sizes the buffers do not have.
void CudaJointSystem::upload(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                             const NeighbourhoodPattern& pattern) {
  try {
    copy_to_device(frames, camera, pattern);
  } catch (...) {
    Device& d = *device_;
    d.width = d.height = 0;
    d.pattern_size = 0;
    linearized_ = proposed_ = false;
    state_ = JointState{};
    candidate_poses_.clear();
    throw;
  }
}

void CudaJointSystem::copy_to_device(const std::vector<VertexMap>& frames,
                                     const CameraIntrinsics& camera,
                                     const NeighbourhoodPattern& pattern) {
  const std::size_t pixels = frames[0].size();
  Device& d = *device_;
  const DrainOnUnwind drain(d.stream);
  linearized_ = proposed_ = false;
  d.width = frames[0].width();
  d.height = frames[0].height();
  d.pattern_size = static_cast<int>(pattern.offsets.size());
  d.camera = PinholeProjection{camera.fx, camera.fy, camera.cx, camera.cy};
  d.reserve(pixels, pattern.offsets.size(), d.blocks(), precision_);
  const cudaStream_t stream = d.stream;
  for (int j = 0; j < 2; ++j)
    JPCR_CUDA_CHECK(
        cudaMemcpyAsync(d.vertices[j].data(), frames[static_cast<std::size_t>(j)].data(),
                        pixels * sizeof(Eigen::Vector3f), cudaMemcpyHostToDevice, stream));
  JPCR_CUDA_CHECK(cudaMemcpyAsync(d.pattern.data(), pattern.offsets.data(),
                                  pattern.offsets.size() * sizeof(PixelOffset),
                                  cudaMemcpyHostToDevice, stream));
  JPCR_CUDA_CHECK(cudaMemcpyAsync(d.quadrics.data(), state_.quadrics.data(),
                                  pixels * sizeof(Quadricd), cudaMemcpyHostToDevice, stream));
  JPCR_CUDA_CHECK(
      cudaMemcpyAsync(d.valid.data(), state_.valid.data(), pixels, cudaMemcpyHostToDevice, stream));
  JPCR_CUDA_CHECK(cudaStreamSynchronize(stream));
  host_quadrics_fresh_ = true;
  candidate_poses_ = state_.poses;
}

template <typename Scalar>
void CudaJointSystem::launch_linearize(double lambda) {
  Device& d = *device_;
  linearize_pair<Scalar><<<d.grid(), dim3(kBlockWidth, kBlockHeight), 0, d.stream>>>(
      d.inputs<Scalar>(state_.poses), d.quadrics.data(), d.valid.data(), params_, Scalar(lambda),
      reinterpret_cast<Scalar*>(d.factors.data()), d.active.data(), d.partials.data());
  JPCR_CUDA_CHECK_LAUNCH("linearize_pair", d.stream);
}

ReducedSystem CudaJointSystem::linearize(double lambda) {
  Device& d = *device_;
  const DeviceScope scope(d.device);
  const DrainOnUnwind drain(d.stream);
  const cudaStream_t stream = d.stream;
  linearized_ = proposed_ = false;
  if (d.pixels() == 0) {  // an empty frame (or nothing loaded): no quadric takes part
    ReducedSystem none;
    none.S = Eigen::MatrixXd::Zero(6, 6);
    none.s = none.A_diagonal = Eigen::VectorXd::Zero(6);
    none.seen = {0};
    linearized_ = true;
    return none;
  }
  d.record(0);
  if (poison_) {
    poison(d.factors, Device::factor_doubles(d.pixels(), precision_), stream);
    poison(d.active, d.pixels(), stream);
    poison(d.partials, static_cast<std::size_t>(d.blocks()) * kSums, stream);
  }
  if (precision_ == CudaPrecision::kDouble)
    launch_linearize<double>(lambda);
  else
    launch_linearize<float>(lambda);
  d.download_totals(kSums);
  d.record(1);
  JPCR_CUDA_CHECK(cudaStreamSynchronize(stream));
  timing_.linearize_ms = d.elapsed_ms(0, 1);

  const double* t = d.host_totals;
  ReducedSystem out;
  out.S.resize(6, 6);
  for (int r = 0, n = 0; r < 6; ++r)
    for (int c = 0; c <= r; ++c, ++n)
      out.S(r, c) = out.S(c, r) = t[n];
  out.s = Eigen::Map<const Eigen::VectorXd>(t + kRhs, 6);
  out.A_diagonal = Eigen::Map<const Eigen::VectorXd>(t + kDiagA, 6);
  out.cost = t[kCost];
  out.terms = static_cast<long>(t[kTerms]);  // exact: integers far below 2⁵³
  out.active = static_cast<int>(t[kActive]);
  out.seen = {static_cast<int>(t[kSeen])};
  linearized_ = true;
  return out;
}

template <typename Scalar>
void CudaJointSystem::launch_step(const Vector6d& pose_step) {
  Device& d = *device_;
  PoseStep<Scalar> step;
  for (int k = 0; k < 6; ++k)
    step.xi[k] = Scalar(pose_step(k));
  step_pair<Scalar><<<d.grid(), dim3(kBlockWidth, kBlockHeight), 0, d.stream>>>(
      d.inputs<Scalar>(state_.poses), d.inputs<Scalar>(candidate_poses_), d.quadrics.data(),
      d.active.data(), reinterpret_cast<const Scalar*>(d.factors.data()), params_, step,
      d.candidate.data(), d.partials.data());
  JPCR_CUDA_CHECK_LAUNCH("step_pair", d.stream);
}

double CudaJointSystem::propose(const ReducedSystem& /*system*/, double /*lambda*/,
                                const std::vector<Vector6d>& pose_steps) {
  if (pose_steps.size() != 1)
    throw std::invalid_argument("CudaJointSystem: J-ftf has exactly one pose step");
  if (state_.poses.size() != 2 || !linearized_)
    throw std::logic_error("CudaJointSystem: propose() before linearize() of a loaded pair");
  // T ← exp(Δξ^) T, re-orthonormalised, as JointSystem::step; the factors are those of the last
  // linearize (the loop of joint_problem.hpp always proposes from the latest linearisation).
  Eigen::Isometry3d T = se3_exp(pose_steps[0]) * state_.poses[1];
  T.linear() = orthonormalize(T.linear());
  candidate_poses_ = {Eigen::Isometry3d::Identity(), T};
  Device& d = *device_;
  const DeviceScope scope(d.device);
  const DrainOnUnwind drain(d.stream);
  const cudaStream_t stream = d.stream;
  proposed_ = false;
  if (d.pixels() == 0) {
    proposed_ = true;
    return 0.0;
  }
  d.record(2);
  if (poison_) {
    poison(d.candidate, d.pixels(), stream);
    poison(d.partials, static_cast<std::size_t>(d.blocks()), stream);
  }
  if (precision_ == CudaPrecision::kDouble)
    launch_step<double>(pose_steps[0]);
  else
    launch_step<float>(pose_steps[0]);
  d.download_totals(1);
  d.record(3);
  JPCR_CUDA_CHECK(cudaStreamSynchronize(stream));
  timing_.propose_ms = d.elapsed_ms(2, 3);
  proposed_ = true;
  return d.host_totals[0];
}

void CudaJointSystem::accept() {
  if (!proposed_) throw std::logic_error("CudaJointSystem: accept() without a propose()");
  // The candidate buffer now holds the replaced quadrics, and the factors are the replaced
  // state's: the next propose() needs a fresh linearize().
  linearized_ = proposed_ = false;
  std::swap(device_->quadrics, device_->candidate);
  state_.poses = candidate_poses_;
  host_quadrics_fresh_ = false;
}

const JointState& CudaJointSystem::state() {
  if (!host_quadrics_fresh_) {
    Device& d = *device_;
    const DeviceScope scope(d.device);
    const DrainOnUnwind drain(d.stream);
    state_.quadrics.resize(d.pixels());
    JPCR_CUDA_CHECK(cudaMemcpyAsync(state_.quadrics.data(), d.quadrics.data(),
                                    d.pixels() * sizeof(Quadricd), cudaMemcpyDeviceToHost,
                                    d.stream));
    JPCR_CUDA_CHECK(cudaStreamSynchronize(d.stream));
    host_quadrics_fresh_ = true;
  }
  return state_;
}

JointState CudaJointSystem::candidate() {
  if (!proposed_) throw std::logic_error("CudaJointSystem: candidate() without a propose()");
  Device& d = *device_;
  const DeviceScope scope(d.device);
  JointState c;  // before the drain, which must wait for the copy into it on an exception
  const DrainOnUnwind drain(d.stream);
  c.poses = candidate_poses_;
  c.valid = state_.valid;
  c.quadrics.resize(d.pixels());
  JPCR_CUDA_CHECK(cudaMemcpyAsync(c.quadrics.data(), d.candidate.data(),
                                  d.pixels() * sizeof(Quadricd), cudaMemcpyDeviceToHost, d.stream));
  JPCR_CUDA_CHECK(cudaStreamSynchronize(d.stream));
  return c;
}

std::vector<PairFactors> CudaJointSystem::factors() {
  if (!linearized_) throw std::logic_error("CudaJointSystem: factors() without a linearize()");
  Device& d = *device_;
  const DeviceScope scope(d.device);
  const std::size_t pixels = d.pixels();
  std::vector<unsigned char> active(pixels);
  const std::size_t scalar = precision_ == CudaPrecision::kDouble ? sizeof(double) : sizeof(float);
  std::vector<unsigned char> raw(kFactors * pixels * scalar);
  const DrainOnUnwind drain(d.stream);  // after the copies' destinations: destroyed before them
  JPCR_CUDA_CHECK(
      cudaMemcpyAsync(active.data(), d.active.data(), pixels, cudaMemcpyDeviceToHost, d.stream));
  JPCR_CUDA_CHECK(
      cudaMemcpyAsync(raw.data(), d.factors.data(), raw.size(), cudaMemcpyDeviceToHost, d.stream));
  JPCR_CUDA_CHECK(cudaStreamSynchronize(d.stream));
  auto at = [&](int f, std::size_t i) {
    const std::size_t k = static_cast<std::size_t>(f) * pixels + i;
    return scalar == sizeof(double) ? reinterpret_cast<const double*>(raw.data())[k]
                                    : double(reinterpret_cast<const float*>(raw.data())[k]);
  };
  std::vector<PairFactors> out;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (active[i] == 0) continue;
    PairFactors f;
    f.pixel = i;
    for (int r = 0; r < 6; ++r)
      f.k(r) = at(r, i);
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < 6; ++r)
        f.K(r, c) = at(6 + 6 * c + r, i);
    out.push_back(f);
  }
  return out;
}

std::size_t CudaJointSystem::device_allocations() const {
  return device_->allocations;
}

CudaJointFrameToFrame::CudaJointFrameToFrame(const JointParams& params, CudaPrecision precision)
    : params_(params) {
  params_.validate();
  system_ = std::make_unique<CudaJointSystem>(params_.terms(true), precision);
}

CudaJointFrameToFrame::~CudaJointFrameToFrame() = default;

RefinementResult CudaJointFrameToFrame::refine(const std::vector<VertexMap>& vertices,
                                               const CameraIntrinsics& camera,
                                               const std::vector<Eigen::Isometry3d>& initial_poses,
                                               const QuadricMap& initial_quadrics) const {
  if (vertices.size() != 2) throw std::invalid_argument("j-ftf: needs exactly two frames");
  check_joint_inputs(vertices, camera, initial_poses, initial_quadrics);
  // The host's work before and after the loop touches no device state: only the loop holds the
  // lock, so another thread's pair can use the device meanwhile.
  const std::vector<unsigned char> edges = edge_quadrics(vertices[0], params_);
  int left_out = 0;
  RefinementResult result;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    left_out = system_->load(vertices, camera, params_.quadric.pattern_for(camera.width),
                             initial_poses, initial_quadrics, edges);
    result = run_joint_refinement(*system_, params_, true, name(), initial_quadrics, vertices[0]);
  }
  result.report.device = "cuda";
  result.report.edge_quadrics = left_out;
  if (params_.keep_lower_cost_fit && result.report.iterations > 0)  // on the host, as the CPU
    result.report.quad_it_fits_restored = keep_lower_cost_fits(
        vertices, camera, result.poses, params_, initial_quadrics, result.quadrics);
  return result;
}

std::size_t CudaJointFrameToFrame::device_allocations() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return system_->device_allocations();
}

}  // namespace jpcr
