#include "jpcr/cuda/device_memory.hpp"

#include <utility>

#include <cuda_runtime_api.h>

#include "jpcr/cuda/cuda_check.hpp"

namespace jpcr {

DeviceMemory::~DeviceMemory() {
  release();
}

DeviceMemory::DeviceMemory(DeviceMemory&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)), bytes_(std::exchange(other.bytes_, 0)) {}

DeviceMemory& DeviceMemory::operator=(DeviceMemory&& other) noexcept {
  if (this != &other) {
    release();
    data_ = std::exchange(other.data_, nullptr);
    bytes_ = std::exchange(other.bytes_, 0);
  }
  return *this;
}

bool DeviceMemory::reserve(std::size_t bytes) {
  if (bytes <= bytes_) return false;
  release();
  JPCR_CUDA_CHECK(cudaMalloc(&data_, bytes));
  bytes_ = bytes;
  return true;
}

void DeviceMemory::release() {
  if (data_ != nullptr) cudaFree(data_);  // no throw from a destructor; a failed free is moot
  data_ = nullptr;
  bytes_ = 0;
}

}  // namespace jpcr
