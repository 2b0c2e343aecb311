// GPU Quad IT speed (issue 7: ≤ 1 ms per 640x480 frame on an H100) at 320x240 and 640x480 with
// the reference 129-sample pattern (r = 6, s = 3 at both sizes) and 3 iterations, on rendered
// room_spheres frames with range:1 noise (never zeros; three frames in rotation). Times are CUDA
// events around each stage (CudaQuadricFitTiming), after a warm-up, median of --runs (≥ 20)
// runs; "host" is the wall time of estimate() including the QuadricMap allocation. Rows: double
// with normals given, double with normals on the GPU, float with normals given, and the CPU
// QuadricFit (median of 5). Exits 0 with a message when there is no GPU.
//
//   bench_cuda_quadric [--runs N] [--warmup N] [--no-cpu] [--width 320|640]
//                      [--noise-matched]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "cuda_bench_options.hpp"
#include "jpcr/cuda/cuda_quadric_fit.hpp"
#include "jpcr/cuda/device_selection.hpp"
#include "jpcr/io/synthetic_sequence.hpp"

namespace {

using jpcr::bench::median;
using jpcr::bench::ms_since;

struct Inputs {
  std::vector<jpcr::VertexMap> vertices;
  std::vector<jpcr::NormalMap> normals;
};

Inputs frames(int width, const jpcr::QuadricParams& params) {
  jpcr::SyntheticSequenceOptions options;
  options.frames = 3;
  options.noise = "range:1";
  options.width = width;
  options.height = width * 3 / 4;
  const jpcr::SyntheticSequence seq = jpcr::make_synthetic_sequence(options);
  Inputs in;
  for (int i = 0; i < options.frames; ++i) {
    const jpcr::Frame f = seq.load(i);
    in.vertices.push_back(jpcr::compute_vertex_map(f.depth, f.camera));
    in.normals.push_back(jpcr::estimate_normals(in.vertices.back(), params.normals));
  }
  return in;
}

void gpu_row(int width, jpcr::CudaPrecision precision, bool device_normals,
             const jpcr::bench::CudaBenchOptions& o) {
  jpcr::QuadricParams params;
  jpcr::bench::bench_quadric_params(width, o, params);
  const Inputs in = frames(width, params);
  const jpcr::CudaQuadricFit fit(params, precision);
  for (int i = 0; i < o.warmup; ++i)
    fit.estimate(in.vertices[i % 3], in.normals[i % 3]);
  std::vector<double> kernel, upload, normals, download, total, host;
  std::size_t valid = 0;
  for (int i = 0; i < o.runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const jpcr::QuadricMap map = device_normals
                                     ? fit.estimate(in.vertices[i % 3])
                                     : fit.estimate(in.vertices[i % 3], in.normals[i % 3]);
    host.push_back(ms_since(start));
    const jpcr::CudaQuadricFitTiming t = fit.last_timing();
    kernel.push_back(t.kernel_ms);
    upload.push_back(t.upload_ms);
    normals.push_back(t.normals_ms);
    download.push_back(t.download_ms);
    total.push_back(t.total_ms);
    valid = map.valid_count();
  }
  std::printf("%4dx%-4d %7d  %-6s  %-7s  %8.3f  %8.3f  %8.3f  %8.3f  %8.3f  %8.3f  %6.1f%%\n",
              width, width * 3 / 4, params.pattern.for_width(width).size(),
              precision == jpcr::CudaPrecision::kDouble ? "double" : "float",
              device_normals ? "gpu" : "given", median(kernel), median(normals), median(upload),
              median(download), median(total), median(host), 100.0 * valid / in.vertices[0].size());
}

void cpu_row(int width, const jpcr::bench::CudaBenchOptions& o) {
  jpcr::QuadricParams params;
  jpcr::bench::bench_quadric_params(width, o, params);
  const Inputs in = frames(width, params);
  const jpcr::QuadricFit fit(params);
  fit.estimate(in.vertices[0], in.normals[0]);
  std::vector<double> host;
  for (int i = 0; i < 5; ++i) {
    const auto start = std::chrono::steady_clock::now();
    fit.estimate(in.vertices[i % 3], in.normals[i % 3]);
    host.push_back(ms_since(start));
  }
  std::printf("%4dx%-4d %7d  %-6s  %-7s  %8s  %8s  %8s  %8s  %8s  %8.3f\n", width, width * 3 / 4,
              params.pattern.for_width(width).size(), "cpu", "given", "-", "-", "-", "-", "-",
              median(host));
}

}  // namespace

int main(int argc, char** argv) {
  jpcr::bench::CudaBenchOptions o;
  const int status = jpcr::bench::parse_cuda_bench_options(argc, argv, "bench_cuda_quadric",
                                                           "GPU Quad IT: ms per frame", o);
  if (status >= 0) return status;
  const jpcr::CudaDeviceInfo& gpu = jpcr::query_cuda_device();
  if (!gpu.available) {
    std::printf("bench_cuda_quadric: no CUDA device (%s); nothing to time\n",
                gpu.description.c_str());
    return 0;
  }
  std::printf("Quad IT per frame on %s: CUDA events, %d warm-up, median of %d runs (ms)\n",
              gpu.description.c_str(), o.warmup, o.runs);
  std::printf("%-9s %7s  %-6s  %-7s  %8s  %8s  %8s  %8s  %8s  %8s  %7s\n", "size", "samples",
              "type", "normals", "fit", "normals", "upload", "download", "total", "host", "valid");
  for (int width : o.widths) {
    gpu_row(width, jpcr::CudaPrecision::kDouble, false, o);
    gpu_row(width, jpcr::CudaPrecision::kDouble, true, o);
    gpu_row(width, jpcr::CudaPrecision::kFloat, false, o);
    if (o.cpu) cpu_row(width, o);
  }
  std::printf(
      "fit = the Quad IT kernel; normals = the plane-normal kernel (gpu) or given (computed "
      "on the CPU, not timed); total = upload to download (events); host = estimate() "
      "wall time, with the QuadricMap allocation\n");
  return 0;
}
