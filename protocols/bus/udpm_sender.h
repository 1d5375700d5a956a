// A paced sender of LCM's UDP multicast wire format, for messages of several megabytes (organized
// clouds of 3D cameras: 1120 x 800 x 3 floats = 10.7 MB).
//
// Why: liblcm (1.3.1) sends every fragment of a message back to back in one publish call (165
// datagrams of 65,507 bytes for a PhotoNeo cloud, a few milliseconds on loopback). The kernel
// delivers them into each subscriber's socket buffer, whose size is capped by net.core.rmem_max
// (4 MB on our machines, 8 MB of accounted memory after the kernel's doubling). A message larger
// than that buffer survives only if the subscriber's receive thread drains the socket during the
// burst; on a loaded machine it often does not run, fragments are dropped and the whole message
// is lost. This sender emits the same datagrams (LCM "LC03" fragments, received by unmodified
// liblcm subscribers) in bursts of at most `burst_bytes`, sleeping `gap` between bursts, so that a
// receiver only has to run once per gap instead of during the few milliseconds of the burst.
// It has its own socket, hence its own source port: liblcm reassembles per (sender address,
// sequence number), so its sequence numbers never collide with the liblcm sender of the process.
#pragma once

#include <netinet/in.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal {

// Where a udpm:// URL sends: multicast group, port and TTL.
struct UdpmEndpoint {
  in_addr group{};
  std::uint16_t port = 7667;  // host byte order
  int ttl = 0;
};

// Parses "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=N" (liblcm's defaults for missing parts;
// other options are liblcm's and ignored here). Error when the URL is not udpm:// or malformed.
Expected<UdpmEndpoint> ParseUdpmUrl(const std::string& url);

// The LCM URL liblcm uses for `url`: `url` itself, or LCM_DEFAULT_URL, or liblcm's default.
std::string EffectiveLcmUrl(const std::string& url);

struct PublishPacing {
  std::size_t burst_bytes = 0;       // 0: pacing off; messages larger than this are paced
  std::chrono::microseconds gap{0};  // pause between two bursts
};

// LCM's fragment layout (lcm_udpm.c): a 20-byte big-endian header {magic "LC03", sequence number,
// message size, fragment offset, uint16 fragment number, uint16 fragment count}; the first fragment
// carries the NUL-terminated channel before its data; each fragment carries at most
// kLcmFragmentPayload bytes of channel + data.
inline constexpr std::size_t kLcmFragmentPayload = 65487;
inline constexpr std::size_t kLcmFragmentHeader = 20;

// One datagram: header, then (first fragment only) the channel and a NUL, then
// data[data_offset, data_offset + data_size). Sent with sendmsg and an iovec: no copy of the data.
struct LcmFragment {
  std::uint8_t header[kLcmFragmentHeader];
  bool carries_channel = false;
  std::size_t data_offset = 0;
  std::size_t data_size = 0;
};

// The fragments of one message (pure). Error if the channel is longer than LCM's 63 characters
// or the message needs more than 65,535 fragments.
Expected<std::vector<LcmFragment>> PlanLcmFragments(std::size_t channel_size, std::size_t data_size,
                                                    std::uint32_t sequence_number);

class PacedUdpmSender {
 public:
  static Expected<std::unique_ptr<PacedUdpmSender>> Open(const UdpmEndpoint& endpoint,
                                                         PublishPacing pacing);
  ~PacedUdpmSender();
  PacedUdpmSender(const PacedUdpmSender&) = delete;
  PacedUdpmSender& operator=(const PacedUdpmSender&) = delete;

  // Sends one message as LC03 fragments (always fragmented, even when small), paced.
  Status Publish(const std::string& channel, std::span<const std::uint8_t> data);
  const PublishPacing& pacing() const { return pacing_; }

 private:
  PacedUdpmSender(int fd, sockaddr_in destination, PublishPacing pacing)
      : fd_(fd), destination_(destination), pacing_(pacing) {}
  int fd_;
  sockaddr_in destination_;
  PublishPacing pacing_;
  std::uint32_t sequence_number_ = 0;
};

}  // namespace selfcal
