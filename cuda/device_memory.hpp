// Device memory owned by RAII (issue 7: buffers reused across iterations and frames, no
// per-iteration allocation). Plain C++: the CUDA calls live in device_memory.cpp.
#pragma once

#include <cstddef>

namespace jpcr {

/// One cudaMalloc'ed block. reserve() grows it only when asked for more bytes than it holds, so
/// a buffer sized for the first frame is reused by every later frame of that size. The block is
/// allocated on the calling thread's current device and freed on that device.
class DeviceMemory {
 public:
  DeviceMemory() = default;
  ~DeviceMemory();
  DeviceMemory(const DeviceMemory&) = delete;
  DeviceMemory& operator=(const DeviceMemory&) = delete;
  DeviceMemory(DeviceMemory&& other) noexcept;
  DeviceMemory& operator=(DeviceMemory&& other) noexcept;

  /// Ensures at least `bytes` bytes; returns true when it had to (re)allocate (contents lost).
  bool reserve(std::size_t bytes);
  void release();

  void* data() const { return data_; }
  std::size_t bytes() const { return bytes_; }

 private:
  void* data_ = nullptr;
  std::size_t bytes_ = 0;
  int device_ = 0;  // where data_ lives
};

/// A typed view of DeviceMemory: `count` elements of T.
template <typename T>
class DeviceArray {
 public:
  bool reserve(std::size_t count) { return memory_.reserve(count * sizeof(T)); }
  T* data() const { return static_cast<T*>(memory_.data()); }
  std::size_t capacity() const { return memory_.bytes() / sizeof(T); }

 private:
  DeviceMemory memory_;
};

}  // namespace jpcr
