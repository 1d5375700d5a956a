#include "protocols/camera/stream_options.h"

namespace selfcal::camera {

void DescribeRequestStreamOptions(program::Program& p, std::string& lcm_url, std::string& trigger,
                                  StreamOptions& stream) {
  p.LcmUrlOption(lcm_url);
  p.Option("--channel", stream.channel, "channel of the depth images");
  p.Option("--trigger", trigger,
           "none (every frame) or request (one frame per scan_marker_t BEGIN)")
      ->check(CLI::IsMember({"none", "request"}));
  p.Option("--trigger-channel", stream.trigger_channel, "scan_marker_t channel of the requests");
  p.Option("--max-frames", stream.max_frames, "exit after publishing this many frames (0: never)");
}

}  // namespace selfcal::camera
