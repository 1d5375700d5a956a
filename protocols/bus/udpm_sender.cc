#include "protocols/bus/udpm_sender.h"

#include <arpa/inet.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <thread>

namespace selfcal {
namespace {

constexpr std::uint32_t kMagicLong = 0x4c433033;  // "LC03"
constexpr std::size_t kMaxChannel = 63;           // LCM_MAX_CHANNEL_NAME_LENGTH
constexpr const char* kDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";

void PutU32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}
void PutU16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}

bool ParseInt(const std::string& text, long min, long max, long& out) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (errno != 0 || *end != '\0' || value < min || value > max) return false;
  out = value;
  return true;
}

}  // namespace

std::string EffectiveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  if (env != nullptr && *env != '\0') return env;
  return kDefaultUrl;
}

Expected<UdpmEndpoint> ParseUdpmUrl(const std::string& url) {
  constexpr std::string_view kScheme = "udpm://";
  if (url.rfind(kScheme, 0) != 0) return Error{"'" + url + "' is not a udpm:// URL"};
  std::string rest = url.substr(kScheme.size());
  std::string options;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    options = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  UdpmEndpoint endpoint;
  std::string host = rest.empty() ? "239.255.76.67" : rest;
  if (const auto colon = rest.find(':'); colon != std::string::npos) {
    host = rest.substr(0, colon);
    long port = 0;
    if (!ParseInt(rest.substr(colon + 1), 0, 65535, port)) {
      return Error{"'" + url + "': bad port '" + rest.substr(colon + 1) + "'"};
    }
    endpoint.port = static_cast<std::uint16_t>(port);
  }
  if (inet_aton(host.c_str(), &endpoint.group) == 0) {
    return Error{"'" + url + "': bad multicast address '" + host + "'"};
  }
  std::size_t start = 0;
  while (start < options.size()) {
    auto end = options.find('&', start);
    if (end == std::string::npos) end = options.size();
    const std::string option = options.substr(start, end - start);
    start = end + 1;
    const auto eq = option.find('=');
    if (eq == std::string::npos || option.substr(0, eq) != "ttl") continue;  // liblcm's business
    long ttl = 0;
    if (!ParseInt(option.substr(eq + 1), 0, 255, ttl)) {
      return Error{"'" + url + "': bad ttl '" + option.substr(eq + 1) + "'"};
    }
    endpoint.ttl = static_cast<int>(ttl);
  }
  return endpoint;
}

Expected<std::vector<LcmFragment>> PlanLcmFragments(std::size_t channel_size, std::size_t data_size,
                                                    std::uint32_t sequence_number) {
  if (channel_size > kMaxChannel) {
    return Error{"LCM channel name of " + std::to_string(channel_size) + " characters (at most " +
                 std::to_string(kMaxChannel) + ")"};
  }
  const std::size_t payload = channel_size + 1 + data_size;
  const std::size_t count = (payload + kLcmFragmentPayload - 1) / kLcmFragmentPayload;
  if (count > 65535 || data_size > 0xFFFFFFFFu) {
    return Error{"LCM message of " + std::to_string(data_size) +
                 " bytes needs more than 65535 fragments"};
  }
  std::vector<LcmFragment> fragments(count);
  std::size_t offset = 0;
  for (std::size_t i = 0; i < count; ++i) {
    LcmFragment& f = fragments[i];
    f.carries_channel = i == 0;
    const std::size_t room = kLcmFragmentPayload - (i == 0 ? channel_size + 1 : 0);
    f.data_offset = offset;
    f.data_size = std::min(room, data_size - offset);
    PutU32(f.header, kMagicLong);
    PutU32(f.header + 4, sequence_number);
    PutU32(f.header + 8, static_cast<std::uint32_t>(data_size));
    PutU32(f.header + 12, static_cast<std::uint32_t>(offset));
    PutU16(f.header + 16, static_cast<std::uint16_t>(i));
    PutU16(f.header + 18, static_cast<std::uint16_t>(count));
    offset += f.data_size;
  }
  return fragments;
}

Expected<std::unique_ptr<PacedUdpmSender>> PacedUdpmSender::Open(const UdpmEndpoint& endpoint,
                                                                 PublishPacing pacing) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return Error{std::string("paced LCM sender: socket: ") + std::strerror(errno)};
  const unsigned char ttl = static_cast<unsigned char>(endpoint.ttl);
  const unsigned char loop = 1;  // subscribers on this host, as liblcm does
  if (::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) < 0 ||
      ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) < 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return Error{"paced LCM sender: multicast options: " + why};
  }
  sockaddr_in destination{};
  destination.sin_family = AF_INET;
  destination.sin_addr = endpoint.group;
  destination.sin_port = htons(endpoint.port);
  return std::unique_ptr<PacedUdpmSender>(new PacedUdpmSender(fd, destination, pacing));
}

PacedUdpmSender::~PacedUdpmSender() { ::close(fd_); }

Status PacedUdpmSender::Publish(const std::string& channel, std::span<const std::uint8_t> data) {
  auto plan = PlanLcmFragments(channel.size(), data.size(), sequence_number_);
  if (!plan) return plan.error();
  ++sequence_number_;
  std::size_t burst = 0;
  for (std::size_t i = 0; i < plan->size(); ++i) {
    LcmFragment& f = (*plan)[i];
    iovec parts[3];
    std::size_t n = 0;
    parts[n++] = {f.header, kLcmFragmentHeader};
    if (f.carries_channel) parts[n++] = {const_cast<char*>(channel.c_str()), channel.size() + 1};
    parts[n++] = {const_cast<std::uint8_t*>(data.data() + f.data_offset), f.data_size};
    msghdr message{};
    message.msg_name = &destination_;
    message.msg_namelen = sizeof destination_;
    message.msg_iov = parts;
    message.msg_iovlen = n;
    const std::size_t size =
        kLcmFragmentHeader + (f.carries_channel ? channel.size() + 1 : 0) + f.data_size;
    if (pacing_.burst_bytes > 0 && burst > 0 && burst + size > pacing_.burst_bytes) {
      std::this_thread::sleep_for(pacing_.gap);
      burst = 0;
    }
    ssize_t sent = -1;
    do {
      sent = ::sendmsg(fd_, &message, 0);
    } while (sent < 0 && errno == EINTR);
    if (sent != static_cast<ssize_t>(size)) {
      return Error{"paced LCM sender: fragment " + std::to_string(i) + " of " +
                   std::to_string(plan->size()) + " on " + channel + ": " +
                   (sent < 0 ? std::strerror(errno) : "short send")};
    }
    burst += size;
  }
  return OkStatus();
}

}  // namespace selfcal
