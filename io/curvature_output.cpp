#include "jpcr/io/curvature_output.hpp"

#include <cstring>
#include <sstream>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/npy.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // x86/ARM are little-endian, as the header says
  out.append(bytes, sizeof(T));
}

}  // namespace

void write_curvature_npy(const std::string& path, const CurvatureImage& curvature) {
  write_npy<float>(path,
                   {static_cast<std::size_t>(curvature.height()),
                    static_cast<std::size_t>(curvature.width()), 2},
                   curvature.empty() ? nullptr : curvature.data()->data());
}

CurvatureImage read_curvature_npy(const std::string& path) {
  const NpyArray array = read_npy(path);
  if (array.shape.size() != 3 || array.shape[2] != 2 || array.shape[0] == 0 ||
      array.shape[1] == 0 || array.shape[0] > 1 << 16 || array.shape[1] > 1 << 16) {
    throw InputError(path + ": expected a curvature map of shape H x W x 2");
  }
  // Curvature in 1/m is real-valued; an integer array is some other image, not a map to score.
  if (array.dtype != "f4" && array.dtype != "f8")
    throw InputError(path + ": a curvature map must be float32 or float64, got dtype '" +
                     array.dtype + "'");
  const std::vector<float> values = array.to_float();
  CurvatureImage image(static_cast<int>(array.shape[1]), static_cast<int>(array.shape[0]),
                       Eigen::Vector2f::Zero());
  for (std::size_t i = 0; i < image.size(); ++i)
    image[i] = Eigen::Vector2f(values[2 * i], values[2 * i + 1]);
  return image;
}

void write_curvature_sd_npy(const std::string& path, const Image<float>& sd) {
  write_npy<float>(path,
                   {static_cast<std::size_t>(sd.height()), static_cast<std::size_t>(sd.width())},
                   sd.empty() ? nullptr : sd.data());
}

Image<float> read_curvature_sd_npy(const std::string& path) {
  const NpyArray array = read_npy(path);
  if (array.shape.size() != 2 || array.shape[0] == 0 || array.shape[1] == 0 ||
      array.shape[0] > 1 << 16 || array.shape[1] > 1 << 16)
    throw InputError(path + ": expected a curvature sd map of shape H x W");
  if (array.dtype != "f4" && array.dtype != "f8")
    throw InputError(path + ": a curvature sd map must be float32 or float64, got dtype '" +
                     array.dtype + "'");
  const std::vector<float> values = array.to_float();
  Image<float> image(static_cast<int>(array.shape[1]), static_cast<int>(array.shape[0]));
  for (std::size_t i = 0; i < image.size(); ++i)
    image[i] = values[i];
  return image;
}

std::string format_curvature_ply(const VertexMap& vertices, const QuadricMap& map,
                                 const CurvatureColorParams& colors) {
  if (vertices.width() != map.width() || vertices.height() != map.height())
    throw std::invalid_argument("format_curvature_ply: vertex map and quadric map differ in size");
  std::size_t count = 0;
  for (int v = 0; v < map.height(); ++v)
    for (int u = 0; u < map.width(); ++u)
      count += map.valid(u, v) && is_valid(vertices(u, v)) ? 1 : 0;
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment jpcr principal curvatures (1/m)\n"
         << "element vertex " << count << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property float nx\nproperty float ny\nproperty float nz\n"
         << "property float k1\nproperty float k2\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  std::string out = header.str();
  out.reserve(out.size() + count * (8 * 4 + 3));
  for (int v = 0; v < map.height(); ++v) {
    for (int u = 0; u < map.width(); ++u) {
      if (!map.valid(u, v) || !is_valid(vertices(u, v))) continue;
      const Eigen::Vector3f& X = vertices(u, v);
      const Eigen::Vector3f n = map.quadrics(u, v).normal();
      const Eigen::Vector2f k = map.curvature(u, v);
      for (float x : {X.x(), X.y(), X.z(), n.x(), n.y(), n.z(), k.x(), k.y()})
        put(out, x);
      const Rgb8 c = curvature_color(k.x(), k.y(), colors.scale);
      put(out, c.r);
      put(out, c.g);
      put(out, c.b);
    }
  }
  return out;
}

void write_curvature_ply(const std::string& path, const VertexMap& vertices, const QuadricMap& map,
                         const CurvatureColorParams& colors) {
  const std::string bytes = format_curvature_ply(vertices, map, colors);
  write_file_atomically(path, [&](std::ostream& out) { out.write(bytes.data(), bytes.size()); });
}

}  // namespace jpcr
