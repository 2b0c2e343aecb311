// A plain row-major image: the value type for depth, vertex, normal and curvature maps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

namespace jpcr {

/// The fill of an image made without one: all-NaN for Eigen's matrices (their default
/// constructor leaves the values uninitialised; NaN is "invalid" in every vertex, normal and
/// curvature map), T{} otherwise (0 for numbers).
template <typename T>
T default_fill() {
  if constexpr (std::is_base_of_v<Eigen::DenseBase<T>, T>) {
    return T::Constant(std::numeric_limits<typename T::Scalar>::quiet_NaN());
  } else {
    return T{};
  }
}

template <typename T>
class Image {
 public:
  Image() = default;
  Image(int width, int height, const T& fill = default_fill<T>()) : width_(width), height_(height) {
    if (width < 0 || height < 0) throw std::invalid_argument("Image: negative size");
    data_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), fill);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t size() const { return data_.size(); }
  bool empty() const { return data_.empty(); }

  /// 2-D bounds check; never test a flat index, which wraps across rows (method.md §2).
  bool in_bounds(int u, int v) const { return u >= 0 && v >= 0 && u < width_ && v < height_; }

  T& operator()(int u, int v) { return data_[index(u, v)]; }
  const T& operator()(int u, int v) const { return data_[index(u, v)]; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  typename std::vector<T>::iterator begin() { return data_.begin(); }
  typename std::vector<T>::iterator end() { return data_.end(); }
  typename std::vector<T>::const_iterator begin() const { return data_.begin(); }
  typename std::vector<T>::const_iterator end() const { return data_.end(); }

 private:
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v) * static_cast<std::size_t>(width_) +
           static_cast<std::size_t>(u);
  }

  int width_ = 0;
  int height_ = 0;
  std::vector<T> data_;
};

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
};

/// Depth in metres along the optical axis; 0 or NaN means no measurement.
using DepthImage = Image<float>;
using ColorImage = Image<Rgb8>;

}  // namespace jpcr
