// The one exception type for bad input: a missing or corrupt file, a malformed line, an invalid
// configuration, a frame that does not fit the stream. Its message names the file (and line or
// key) and the problem, ready to print. The parameter structs' validate() (JointParams,
// PipelineParams, FrontendParams, ...) throw it too, naming the key. Other exception types mean
// something else: std::invalid_argument for arguments that break a function's contract
// (CameraIntrinsics::validate(), which the readers of camera files turn into an InputError
// naming the file; Refiner::refine with the wrong number of frames or a first pose other than
// the identity), std::logic_error and std::out_of_range for a call out of order or an index not
// held, CudaError (cuda/) for a device failure, DdsError (io/dds/) for a Cyclone failure. The
// command-line tools catch all of them and exit 1; an embedding program catching
// std::exception sees them all.
#pragma once

#include <stdexcept>
#include <string>

namespace jpcr {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace jpcr
