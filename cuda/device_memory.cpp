#include "jpcr/cuda/device_memory.hpp"

#include <utility>

#include <cuda_runtime_api.h>

#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/stream_events.hpp"

namespace jpcr {

DeviceMemory::~DeviceMemory() {
  release();
}

DeviceMemory::DeviceMemory(DeviceMemory&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)),
      bytes_(std::exchange(other.bytes_, 0)),
      device_(other.device_) {}

DeviceMemory& DeviceMemory::operator=(DeviceMemory&& other) noexcept {
  if (this != &other) {
    release();
    data_ = std::exchange(other.data_, nullptr);
    bytes_ = std::exchange(other.bytes_, 0);
    device_ = other.device_;
  }
  return *this;
}

bool DeviceMemory::reserve(std::size_t bytes) {
  if (bytes <= bytes_) return false;
  release();
  device_ = DeviceScope::current();
  JPCR_CUDA_CHECK(cudaMalloc(&data_, bytes));
  bytes_ = bytes;
  return true;
}

void DeviceMemory::release() {
  if (data_ != nullptr) {  // no throw from a destructor; a failed free is moot
    const DeviceScope scope(device_, std::nothrow);
    if (cudaFree(data_) != cudaSuccess) cudaGetLastError();
  }
  data_ = nullptr;
  bytes_ = 0;
}

}  // namespace jpcr
