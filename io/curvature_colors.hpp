// Curvature maps people can look at (issue: "a colour-coded curvature PNG with a drawn key").
// Colour encodes the shape, brightness the amount of curvature (Koenderink's shape index and
// curvedness), so spheres, cylinders, saddles and planes read at a glance:
//
//   shape index S = (2/π) atan2(κ₁ + κ₂, κ₁ − κ₂) ∈ [−1, 1]      curvedness C = √((κ₁² + κ₂²)/2)
//
//   S = −1 red (cap: bulges toward the camera, the outside of a ball), −½ yellow (ridge: the
//   outside of a cylinder), 0 green (saddle), +½ cyan (rut: inside of a cylinder), +1 blue (cup).
//   The colour fades to white as C → 0 (planes are white); C ≥ `scale` is fully saturated.
//   Pixels without an estimate are black.
#pragma once

#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct CurvatureColorParams {
  float scale = 10.0f;   // 1/m: curvedness drawn fully saturated (a 10 cm ball)
  bool draw_key = true;  // draw the (κ₂, κ₁) key into the bottom-right corner
  int key_size = 0;      // px; 0 = a quarter of the image height
};

/// The colour of one pair κ₁ ≥ κ₂ (1/m); black for NaN.
Rgb8 curvature_color(float k1, float k2, float scale);

/// The whole map, with the key drawn in the bottom-right corner when asked: a square over
/// κ₂ (left to right, −scale … +scale) and κ₁ (bottom to top), coloured where κ₁ ≥ κ₂, with a
/// frame and axis ticks at 0. Text labels are added by save_curvature_png (OpenCV).
ColorImage render_curvature(const CurvatureImage& curvature,
                            const CurvatureColorParams& params = {});

/// Where render_curvature drew the key (x0, y0, size in px); size 0 when it drew none.
struct KeyPlacement {
  int x0 = 0, y0 = 0, size = 0;
};
KeyPlacement key_placement(int width, int height, const CurvatureColorParams& params);

}  // namespace jpcr
