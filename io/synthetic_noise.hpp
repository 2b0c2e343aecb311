// Depth noise models for synthetic frames (evaluation.md "Data"):
//  - none:     the exact ray-cast depth;
//  - range:K:  Gaussian noise along each ray with σ = K % of the range (the paper's protocol).
//              Scaling the range by (1 + K/100 · g) scales z by the same factor, so the point
//              stays on its pixel's ray;
//  - kinect:   axial σ(z) = 0.0012 + 0.0019 (z − 0.4)² m (Nguyen, Izadi & Lovell, 3DIMPVT 2012),
//              disparity quantisation, a working range, and dropouts at grazing angles and at
//              depth edges (the projector's shadow).
// Every draw comes from CounterRandom(seed, ·, frame) at the pixel's index, so a frame's noise is
// a pure function of (seed, frame index) whatever the thread count.
#pragma once

#include <cstdint>
#include <string>

#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct KinectNoiseParams {
  double sigma_constant = 0.0012;   // m, a in σ(z) = a + b (z − z0)²
  double sigma_quadratic = 0.0019;  // 1/m, b
  double sigma_offset = 0.4;        // m, z0
  double baseline = 0.075;          // m, projector–camera baseline of the disparity
  double disparity_focal = 580.0;   // px, focal length of the disparity image
  double disparity_step = 0.125;    // px, disparity quantisation step (1/8 px); 0 turns it off
  double min_depth = 0.4;           // m, nearer surfaces give no measurement
  double max_depth = 8.0;           // m, farther surfaces give no measurement
  double grazing_start = 70.0;      // deg, incidence angle at which dropouts start
  double grazing_full = 85.0;       // deg, incidence angle beyond which every pixel drops out
  double edge_jump = 0.05;          // a 4-neighbour nearer or farther by this fraction of z (or
                                    // with no surface) makes the pixel a depth-edge pixel
  double edge_dropout = 0.8;        // probability that a depth-edge pixel drops out

  /// Throws InputError "field: problem" for the first invalid field.
  void validate() const;
};

enum class NoiseKind { kNone, kRange, kKinect };

struct NoiseModel {
  NoiseKind kind = NoiseKind::kNone;
  double range_percent = 0.0;  // kRange: σ = range_percent % of the range along the ray
  KinectNoiseParams kinect;    // kKinect

  /// The spec text parse_noise() reads back: "none", "range:1.5", "kinect".
  std::string describe() const;
};

/// Parses "none", "range:K" (K ≥ 0, a percentage of the range, any float) or "kinect"; throws
/// InputError quoting the text otherwise.
NoiseModel parse_noise(const std::string& spec);

/// The noisy depth (m, 0 = no measurement) of a frame from its exact depth (0 where no surface)
/// and camera-frame normals (toward the camera; only the Kinect model reads them).
DepthImage add_depth_noise(const DepthImage& exact, const NormalMap& normals,
                           const CameraIntrinsics& camera, const NoiseModel& noise,
                           std::uint64_t seed, std::uint64_t frame_index);

}  // namespace jpcr
