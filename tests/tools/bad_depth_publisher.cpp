// A test publisher of malformed depth images: jpcr_test_bad_depth DOMAIN TOPIC COUNT publishes
// COUNT sensor_msgs/Image samples that no depth subscriber may accept (an rgb8 encoding, a step
// shorter than a row, data shorter than height * step, in turn) once a subscriber matched, and
// waits for their acknowledgement. The Cyclone configuration comes from $CYCLONEDDS_URI.
// Exits 0, or 1 when no subscriber matched or the samples were not acknowledged within 20 s.
#include <chrono>
#include <cstdlib>
#include <iostream>

#include "jpcr/io/dds/dds_endpoint.hpp"
#include "jpcr/io/dds/ros_messages.hpp"

int main(int argc, char** argv) {
  using namespace jpcr;
  if (argc != 4) {
    std::cerr << "usage: jpcr_test_bad_depth DOMAIN TOPIC COUNT\n";
    return 2;
  }
  const DdsParticipant participant(std::atoi(argv[1]));
  const DdsConfig config;
  const DdsWriter<RosImage> writer(participant, argv[2], DdsQos{true, false, 16});
  constexpr std::chrono::milliseconds kWait{20000};
  if (!writer.wait_matched(1, kWait)) {
    std::cerr << "jpcr_test_bad_depth: no subscriber on " << argv[2] << '\n';
    return 1;
  }
  const int count = std::atoi(argv[3]);
  for (int i = 0; i < count; ++i) {
    RosImageBuffer image;
    image.width = 160;
    image.height = 120;
    image.encoding = "32FC1";
    image.step = 160 * 4;
    if (i % 3 == 0) image.encoding = "rgb8", image.step = 160 * 3;
    if (i % 3 == 1) image.step = 100;  // shorter than a row
    image.data.assign(image.step * image.height - (i % 3 == 2 ? 7 : 0), 0);
    writer.write(image_message(image, 1000.0 + i, config.camera_frame_id));
  }
  if (!writer.wait_for_acks(kWait)) {
    std::cerr << "jpcr_test_bad_depth: samples not acknowledged\n";
    return 1;
  }
  std::cout << "published " << count << " malformed images on " << argv[2] << '\n';
  return 0;
}
