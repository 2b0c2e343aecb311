#include "jpcr/frontend/row_pool.hpp"

#include <algorithm>

namespace jpcr {

RowPool::RowPool(int threads) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int slot = 1; slot < threads; ++slot)
    helpers_.emplace_back([this, slot] { helper(slot); });
}

RowPool::~RowPool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : helpers_)
    t.join();
}

void RowPool::helper(int slot) {
  std::uint64_t seen = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || (job_ != seen && next_ < total_); });
    if (stop_) return;
    seen = job_;
    while (next_ < total_) {
      const int c = next_++;
      const Body* body = body_;
      const int begin = c * chunk_, end = std::min(rows_, begin + chunk_);
      lock.unlock();
      (*body)(begin, end, slot);
      lock.lock();
      if (++done_ == total_) finished_.notify_one();
    }
  }
}

void RowPool::for_rows(int rows, int chunk, const Body& body) {
  if (rows <= 0) return;
  chunk = std::max(1, chunk);
  const int total = (rows + chunk - 1) / chunk;
  if (helpers_.empty() || total == 1) {
    body(0, rows, 0);
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  body_ = &body;
  rows_ = rows;
  chunk_ = chunk;
  next_ = done_ = 0;
  total_ = total;
  ++job_;
  wake_.notify_all();
  while (next_ < total_) {
    const int c = next_++;
    const int begin = c * chunk_, end = std::min(rows_, begin + chunk_);
    lock.unlock();
    body(begin, end, 0);
    lock.lock();
    ++done_;
  }
  finished_.wait(lock, [&] { return done_ == total_; });
  body_ = nullptr;
}

}  // namespace jpcr
