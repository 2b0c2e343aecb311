// cli::Heartbeat: a long step says it is still working, a short one says nothing, and the end of
// the step does not wait out the interval.
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli/heartbeat.hpp"

namespace jpcr::cli {
namespace {

using std::chrono::milliseconds;

struct Lines {
  std::mutex mutex;
  std::vector<std::string> said;
  Heartbeat::Say say() {
    return [this](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      said.push_back(line);
    };
  }
  std::size_t count() {
    std::lock_guard<std::mutex> lock(mutex);
    return said.size();
  }
};

TEST(CliHeartbeat, ALongStepSaysItIsStillWorking) {
  Lines lines;
  {
    const Heartbeat heartbeat("frame 35", milliseconds(20), lines.say());
    // Until two lines came (or 30 s, a hang): how often the thread gets the core is not ours.
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (lines.count() < 2 && std::chrono::steady_clock::now() < give_up)
      std::this_thread::sleep_for(milliseconds(5));
  }
  ASSERT_GE(lines.said.size(), 2u);
  EXPECT_EQ(lines.said[0].rfind("frame 35: still working (", 0), 0u) << lines.said[0];
  EXPECT_EQ(lines.said[0].back(), ')');
}

TEST(CliHeartbeat, AShortStepSaysNothingAndEndsAtOnce) {
  Lines lines;
  const auto start = std::chrono::steady_clock::now();
  { const Heartbeat heartbeat("finishing", std::chrono::minutes(10), lines.say()); }
  // Ending waits for the thread, not for the 10 minutes (a generous bound: a hang, not a speed).
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::minutes(1));
  EXPECT_EQ(lines.count(), 0u);
}

TEST(CliHeartbeat, ALineThatThrowsDoesNotEndTheProgram) {
  int calls = 0;
  std::mutex mutex;
  {
    const Heartbeat heartbeat("frame 1", milliseconds(5), [&](const std::string&) {
      std::lock_guard<std::mutex> lock(mutex);
      ++calls;
      throw std::runtime_error("stderr is closed");
    });
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (calls >= 2 || std::chrono::steady_clock::now() > give_up) break;
      }
      std::this_thread::sleep_for(milliseconds(5));
    }
  }
  EXPECT_GE(calls, 2);  // it went on after the first throw
}

}  // namespace
}  // namespace jpcr::cli
