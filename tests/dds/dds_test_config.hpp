// A DdsConfig for one test process: the loopback Cyclone configuration, a domain and topic names
// of its own (pid-based), so parallel ctest runs never see each other's samples.
#pragma once

#include <unistd.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "jpcr/io/dds/dds_config.hpp"

namespace jpcr::test {

inline DdsConfig loopback_dds_config(const std::string& name) {
  DdsConfig c;
  c.cyclone_uri = "file://" + std::string(JPCR_SOURCE_DIR) + "/configs/cyclonedds_loopback.xml";
  c.domain_id = 1 + static_cast<int>(::getpid() % 200);
  const std::string root = "rt/jpcr_test_" + std::to_string(::getpid()) + "_" + name + "/";
  c.topic_prefix = root;
  c.depth_topic = root + "camera/depth/image_raw";
  c.camera_info_topic = root + "camera/depth/camera_info";
  return c;
}

/// Polls `done` until it is true or `timeout` passed; returns the last value.
inline bool eventually(const std::function<bool()>& done,
                       std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace jpcr::test
