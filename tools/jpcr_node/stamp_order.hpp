// jpcr_node's order of live frames: a frame out of time order is skipped, a new time line (a
// restarted recording or clock) is taken once it is confirmed.
#pragma once

#include <iostream>
#include <limits>
#include <string>

#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/io/log_budget.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr::node {

/// Live frames must come in time order: a frame stamped at or up to kMaxJump before the last one
/// taken (a second publisher, a repeated sample) would be tracked as a motion back in time. A
/// step back of more than kMaxJump is a new time line (a restarted recording, a reset clock) once
/// kConfirmFrames frames in a row, in order, continue it: taken, with one line (rate-limited), so
/// that the node does not skip every later frame. So is a step forward of more than kMaxJump that
/// returns to the time line left at such a jump (at or after its last stamp less kMaxJump), until
/// the new line has passed that stamp; other steps forward are taken at once (a slow sensor, a
/// dropout; before, the first such step after the start cost kConfirmFrames − 1 frames, and a
/// sensor slower than 1 Hz kept one frame in three). So a single stale frame is skipped, and of
/// two publishers whose clocks differ by more than kMaxJump the node follows one: the other's
/// frames never come kConfirmFrames in a row between the first one's (each of them was a new
/// time line before, and the path went back and forth in time). A burst of kConfirmFrames stale
/// frames is indistinguishable from a restarted recording and is taken as one.
class StampOrder {
 public:
  static constexpr double kMaxJump = 1.0;  // s
  static constexpr int kConfirmFrames = 3;

  /// Throws InputError (the input is skipped) when `stamp` is out of order.
  void take(double stamp) {
    if (taken_ && !(stamp > last_) && last_ - stamp <= kMaxJump) {
      line_frames_ = 0;
      throw InputError("frame stamped " + exact(stamp) + " is not after the previous frame (" +
                       exact(last_) + "): out of order or repeated");
    }
    const bool back = stamp < last_ - kMaxJump;
    const bool returns = stamp > last_ + kMaxJump && stamp >= left_ - kMaxJump;
    if (taken_ && (back || returns)) {
      line_frames_ = line_frames_ > 0 && stamp > line_last_ ? line_frames_ + 1 : 1;
      line_last_ = stamp;
      const char* way = back ? "before" : "after";
      if (line_frames_ < kConfirmFrames)
        throw InputError("frame stamped " + exact(stamp) + " is more than " +
                         std::to_string(static_cast<int>(kMaxJump)) + " s " + way +
                         " the previous frame (" + exact(last_) +
                         "): a new time line (a restarted recording or clock) once " +
                         std::to_string(kConfirmFrames) + " frames in a row continue it");
      std::size_t left_out = 0;
      if (line_notes_.allow(left_out))
        std::cerr << "jpcr_node: the stamps jumped by " << stamp - last_ << " s (at "
                  << exact(stamp) << ") for " << kConfirmFrames
                  << " frames in a row: a restarted recording or clock; taken as a new time line"
                  << LogBudget::note(left_out) << "\n";
      left_ = last_;
    }
    line_frames_ = 0;
    last_ = stamp;
    taken_ = true;
    if (last_ >= left_ - kMaxJump) left_ = kNoLineLeft;  // the new line has passed the old one
  }

 private:
  static std::string exact(double stamp) {  // as received: sec.nanosec
    const RosStamp s = to_ros_stamp(stamp);
    return format_ros_stamp(s.sec, s.nanosec);
  }

  bool taken_ = false;
  double last_ = 0.0;
  int line_frames_ = 0;     // frames in a row on a time line away from last_ (not taken yet) ...
  double line_last_ = 0.0;  // ... and the latest of them
  static constexpr double kNoLineLeft = std::numeric_limits<double>::infinity();
  double left_ = kNoLineLeft;  // the last stamp of the time line left at the latest jump back
  LogBudget line_notes_;
};

}  // namespace jpcr::node
