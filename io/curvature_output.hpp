// Writers and readers of curvature results:
//   - .npy float32 H×W×2 (κ₁, κ₂ in 1/m, NaN where invalid), read by numpy.load and jpcr_eval;
//   - .npy float32 H×W of each pixel's sd (1/m, NaN where invalid; curvature_spread.hpp);
//   - a colour PNG with its key (curvature_colors.hpp) and text labels;
//   - a binary PLY point cloud with κ₁, κ₂ as vertex properties, the refined normals and the
//     curvature colour, for CloudCompare and MeshLab.
// Every file is written atomically.
#pragma once

#include <optional>
#include <set>
#include <string>

#include "jpcr/io/curvature_colors.hpp"
#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr {

void write_curvature_npy(const std::string& path, const CurvatureImage& curvature);

/// Reads an H×W×2 float (or double) .npy; throws InputError naming the file when its shape is not
/// H×W×2.
CurvatureImage read_curvature_npy(const std::string& path);

/// The sd map of curvature_spread (H×W float32).
void write_curvature_sd_npy(const std::string& path, const Image<float>& sd);

/// Reads an H×W float (or double) .npy; throws InputError naming the file otherwise.
Image<float> read_curvature_sd_npy(const std::string& path);

/// Vertices with a valid quadric: x y z (m, camera frame), nx ny nz, k1 k2 (1/m), red green blue.
void write_curvature_ply(const std::string& path, const VertexMap& vertices, const QuadricMap& map,
                         const CurvatureColorParams& colors = {});

/// The PLY bytes (binary little-endian), for tests.
std::string format_curvature_ply(const VertexMap& vertices, const QuadricMap& map,
                                 const CurvatureColorParams& colors = {});

/// The colour map with its key and labels as PNG (OpenCV; full profile only).
void save_curvature_png(const std::string& path, const CurvatureImage& curvature,
                        const CurvatureColorParams& colors = {});

/// The per-frame outputs of the curvature tools under one directory: curvature/<stamp>.npy,
/// curvature_png/<stamp>.png, with `spread` curvature_sd/<stamp>.npy (curvature_spread of each
/// map on the vertices it is written with, with the pattern and fit of these parameters) and,
/// with `ply`, ply/<stamp>.ply (full profile only). The directories are created by the
/// constructor.
class CurvatureWriter {
 public:
  CurvatureWriter(std::string directory, bool ply, const CurvatureColorParams& colors = {},
                  std::optional<QuadricParams> spread = std::nullopt);
  /// Writes curvature/STAMP.npy, curvature_png/STAMP.png (and curvature_sd/STAMP.npy,
  /// ply/STAMP.ply). Returns the sd map it wrote (empty without `spread`), for a caller that also
  /// publishes it. Throws InputError for a stamp already written, rather than overwrite that map.
  Image<float> write(const std::string& stamp, const QuadricMap& map,
                     const VertexMap& vertices) const;
  std::size_t written() const { return written_; }
  /// Over the maps written with `spread`: their valid pixels, and those of them without an sd
  /// (curvature_spread withholds it where the gate drops over a tenth of the samples).
  std::size_t sd_valid_pixels() const { return sd_valid_pixels_; }
  std::size_t sd_withheld_pixels() const { return sd_withheld_pixels_; }
  /// A warning for the end of a run when most valid pixels got no sd (more than half), else "".
  std::string sd_warning() const;

 private:
  std::string directory_;
  bool ply_;
  CurvatureColorParams colors_;
  std::optional<QuadricParams> spread_;
  mutable std::size_t written_ = 0;
  mutable std::size_t sd_valid_pixels_ = 0, sd_withheld_pixels_ = 0;
  mutable std::set<std::string> stamps_;  // names written so far
};

}  // namespace jpcr
