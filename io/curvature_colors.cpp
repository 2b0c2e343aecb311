#include "jpcr/io/curvature_colors.hpp"

#include <algorithm>
#include <cmath>

namespace jpcr {

namespace {

// Hue ramp over the shape index: red, yellow, green, cyan, blue at S = −1, −½, 0, ½, 1.
Eigen::Vector3f shape_hue(float S) {
  static const Eigen::Vector3f stops[5] = {
      {1, 0, 0}, {1, 1, 0}, {0, 0.85f, 0}, {0, 1, 1}, {0, 0, 1}};
  const float x = std::clamp((S + 1.0f) * 2.0f, 0.0f, 4.0f);
  const int i = std::min(3, static_cast<int>(x));
  const float t = x - i;
  return (1.0f - t) * stops[i] + t * stops[i + 1];
}

Rgb8 to_rgb(const Eigen::Vector3f& c) {
  auto byte = [](float x) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f));
  };
  return {byte(c.x()), byte(c.y()), byte(c.z())};
}

void draw_key(ColorImage& image, const KeyPlacement& key, float scale) {
  const Rgb8 frame{255, 255, 255}, shadow{40, 40, 40};
  for (int y = 0; y < key.size; ++y) {
    for (int x = 0; x < key.size; ++x) {
      const float k2 = (2.0f * (x + 0.5f) / key.size - 1.0f) * scale;
      const float k1 = (1.0f - 2.0f * (y + 0.5f) / key.size) * scale;
      Rgb8 c = k1 >= k2 ? curvature_color(k1, k2, scale) : shadow;
      const bool border = x == 0 || y == 0 || x == key.size - 1 || y == key.size - 1;
      const bool axis = (x == key.size / 2 || y == key.size / 2) && k1 < k2;
      if (border || axis) c = frame;
      image(key.x0 + x, key.y0 + y) = c;
    }
  }
}

}  // namespace

Rgb8 curvature_color(float k1, float k2, float scale) {
  if (!std::isfinite(k1) || !std::isfinite(k2)) return {0, 0, 0};
  const float S = 2.0f / static_cast<float>(M_PI) * std::atan2(k1 + k2, k1 - k2);
  const float C = std::sqrt(0.5f * (k1 * k1 + k2 * k2));
  const float t = std::clamp(C / scale, 0.0f, 1.0f);
  return to_rgb((1.0f - t) * Eigen::Vector3f::Ones() + t * shape_hue(S));
}

KeyPlacement key_placement(int width, int height, const CurvatureColorParams& params) {
  if (!params.draw_key) return {};
  const int size = params.key_size > 0 ? params.key_size : height / 4;
  const int margin = std::max(2, height / 60);
  if (size < 16 || size + 2 * margin > std::min(width, height)) return {};
  return {width - size - margin, height - size - margin, size};
}

ColorImage render_curvature(const CurvatureImage& curvature, const CurvatureColorParams& params) {
  ColorImage image(curvature.width(), curvature.height());
  for (std::size_t i = 0; i < curvature.size(); ++i)
    image[i] = curvature_color(curvature[i].x(), curvature[i].y(), params.scale);
  const KeyPlacement key = key_placement(curvature.width(), curvature.height(), params);
  if (key.size > 0) draw_key(image, key, params.scale);
  return image;
}

}  // namespace jpcr
