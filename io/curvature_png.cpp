// save_curvature_png (curvature_output.hpp): the colour map with its key and OpenCV text labels.
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/depth_png.hpp"
#include "jpcr/quadric/curvature_spread.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

void label(ColorImage& image, const std::string& text, int x, int y, double size) {
  cv::Mat mat(image.height(), image.width(), CV_8UC3, image.data());  // shares the pixels
  cv::putText(mat, text, {x, y}, cv::FONT_HERSHEY_SIMPLEX, size, cv::Scalar(0, 0, 0), 3,
              cv::LINE_AA);
  cv::putText(mat, text, {x, y}, cv::FONT_HERSHEY_SIMPLEX, size, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

}  // namespace

void save_curvature_png(const std::string& path, const CurvatureImage& curvature,
                        const CurvatureColorParams& colors) {
  ColorImage image = render_curvature(curvature, colors);
  const KeyPlacement key = key_placement(image.width(), image.height(), colors);
  if (key.size >= 64) {
    const double size = key.size / 240.0;
    char range[64];
    std::snprintf(range, sizeof range, "+-%g 1/m", colors.scale);
    label(image, "k2 ->", key.x0 + key.size / 2, key.y0 + key.size - 6, size);
    label(image, "k1", key.x0 + 4, key.y0 + key.size / 6, size);
    label(image, range, key.x0 + 4, key.y0 + key.size / 2 + key.size / 8, size);
  }
  save_color_png(path, image);
}

CurvatureWriter::CurvatureWriter(std::string directory, bool ply,
                                 const CurvatureColorParams& colors,
                                 std::optional<QuadricParams> spread)
    : directory_(std::move(directory)), ply_(ply), colors_(colors), spread_(std::move(spread)) {
  ensure_directory(directory_ + "/curvature");
  ensure_directory(directory_ + "/curvature_png");
  if (spread_) ensure_directory(directory_ + "/curvature_sd");
  if (ply_) ensure_directory(directory_ + "/ply");
}

Image<float> CurvatureWriter::write(const std::string& stamp, const QuadricMap& map,
                                    const VertexMap& vertices) const {
  // Stamps are timestamps at 1 us (format_stamp): frames closer than that would overwrite
  // each other's maps.
  if (!stamps_.insert(stamp).second)
    throw InputError(directory_ + ": two curvature maps are named " + stamp +
                     " (their frames' timestamps agree to 1 us, the resolution of the names)");
  write_curvature_npy(directory_ + "/curvature/" + stamp + ".npy", map.curvature);
  save_curvature_png(directory_ + "/curvature_png/" + stamp + ".png", map.curvature, colors_);
  Image<float> sd;
  if (spread_) {
    sd = curvature_spread(map, vertices, *spread_);
    write_curvature_sd_npy(directory_ + "/curvature_sd/" + stamp + ".npy", sd);
    for (std::size_t i = 0; i < sd.size(); ++i)
      if (map.status[i] == QuadricStatus::kValid) {
        ++sd_valid_pixels_;
        sd_withheld_pixels_ += std::isfinite(sd[i]) ? 0 : 1;
      }
  }
  if (ply_) write_curvature_ply(directory_ + "/ply/" + stamp + ".ply", vertices, map, colors_);
  ++written_;
  return sd;
}

std::string CurvatureWriter::sd_warning() const {
  if (sd_valid_pixels_ == 0 || 2 * sd_withheld_pixels_ <= sd_valid_pixels_) return "";
  char percent[16];
  std::snprintf(percent, sizeof percent, "%.0f",
                100.0 * double(sd_withheld_pixels_) / double(sd_valid_pixels_));
  return std::string("no curvature sd at ") + percent +
         " % of the valid pixels: over a tenth of their samples fall outside quadric.fit's "
         "residual gate, so the gate is likely below the depth noise and the fits are truncated "
         "(README, \"Curvature spread\" and \"Range noise\")";
}

}  // namespace jpcr
