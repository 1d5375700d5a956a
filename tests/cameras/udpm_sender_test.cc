// The paced LCM sender (protocols/bus/udpm_sender.h): fragment layout, URL parsing, and messages
// it sends received byte-identical by an unmodified liblcm subscriber over udpm:// (run inside
// tests/netns-run: the multicast stays on the namespace's loopback).
#include "protocols/bus/udpm_sender.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <vector>

#include "protocols/bus/bus.h"

namespace selfcal {
namespace {

using namespace std::chrono_literals;

std::uint32_t U32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         p[3];
}
std::uint16_t U16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

TEST(UdpmSender, FragmentsCoverTheMessageInLcmLayout) {
  const std::size_t channel = 11;  // "BENCH_CLOUD"
  const std::size_t size = 1120 * 800 * 12 + 48;
  auto plan = PlanLcmFragments(channel, size, 7);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  const std::size_t expected_count =
      (channel + 1 + size + kLcmFragmentPayload - 1) / kLcmFragmentPayload;
  ASSERT_EQ(plan->size(), expected_count);
  std::size_t offset = 0;
  for (std::size_t i = 0; i < plan->size(); ++i) {
    const LcmFragment& f = (*plan)[i];
    EXPECT_EQ(f.carries_channel, i == 0);
    EXPECT_EQ(f.data_offset, offset);
    EXPECT_EQ(U32(f.header), 0x4c433033u);
    EXPECT_EQ(U32(f.header + 4), 7u);
    EXPECT_EQ(U32(f.header + 8), size);
    EXPECT_EQ(U32(f.header + 12), offset);
    EXPECT_EQ(U16(f.header + 16), i);
    EXPECT_EQ(U16(f.header + 18), expected_count);
    const std::size_t datagram_payload = f.data_size + (i == 0 ? channel + 1 : 0);
    if (i + 1 < plan->size()) {
      EXPECT_EQ(datagram_payload, kLcmFragmentPayload) << i;
    }
    offset += f.data_size;
  }
  EXPECT_EQ(offset, size);
}

TEST(UdpmSender, RejectsLongChannelsAndHugeMessages) {
  auto long_channel = PlanLcmFragments(64, 10, 0);
  ASSERT_FALSE(long_channel.ok());
  EXPECT_NE(long_channel.error().message.find("64 characters"), std::string::npos);
  EXPECT_FALSE(PlanLcmFragments(5, std::size_t{65536} * kLcmFragmentPayload, 0).ok());
}

TEST(UdpmSender, ParsesUdpmUrls) {
  auto plain = ParseUdpmUrl("udpm://");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->port, 7667);
  EXPECT_EQ(plain->ttl, 0);
  auto full = ParseUdpmUrl("udpm://239.255.1.2:7700?recv_buf_size=4194304&ttl=1");
  ASSERT_TRUE(full.ok()) << full.error().message;
  EXPECT_EQ(full->port, 7700);
  EXPECT_EQ(full->ttl, 1);
  EXPECT_EQ(ntohl(full->group.s_addr), 0xEFFF0102u);
  EXPECT_FALSE(ParseUdpmUrl("memq://").ok());
  EXPECT_NE(ParseUdpmUrl("udpm://239.255.76.67:70000").error().message.find("bad port"),
            std::string::npos);
  EXPECT_NE(ParseUdpmUrl("udpm://nowhere:7667").error().message.find("bad multicast address"),
            std::string::npos);
  EXPECT_NE(ParseUdpmUrl("udpm://239.255.76.67:7667?ttl=x").error().message.find("bad ttl"),
            std::string::npos);
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(EffectiveLcmUrl(""), "udpm://239.255.76.67:7667?ttl=0");
  ::setenv("LCM_DEFAULT_URL", "udpm://239.255.9.9:7000", 1);
  EXPECT_EQ(EffectiveLcmUrl(""), "udpm://239.255.9.9:7000");
  EXPECT_EQ(EffectiveLcmUrl("memq://"), "memq://");
  ::unsetenv("LCM_DEFAULT_URL");
}

std::vector<std::uint8_t> Pattern(std::size_t size, std::uint32_t seed) {
  std::vector<std::uint8_t> bytes(size);
  std::uint32_t x = seed;
  for (auto& b : bytes) {
    x = x * 1664525u + 1013904223u;
    b = static_cast<std::uint8_t>(x >> 24);
  }
  return bytes;
}

// Paced large messages and liblcm's own small ones, on the same bus, reach a liblcm subscriber
// whole and in order. Sizes: several megabytes, and one that fills its last fragment exactly.
TEST(UdpmSender, LiblcmSubscriberReceivesPacedMessages) {
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  auto subscriber = OpenLcmBus(url);
  ASSERT_TRUE(subscriber.ok()) << subscriber.error().message << " (run inside tests/netns-run)";
  PublishPacing pacing;
  pacing.burst_bytes = 256 * 1024;
  pacing.gap = 200us;
  auto publisher = OpenLcmBus(url, pacing);
  ASSERT_TRUE(publisher.ok()) << publisher.error().message;

  const std::string channel = "PACED_TEST";
  const std::vector<std::vector<std::uint8_t>> sent = {
      Pattern(5'000'000, 1), Pattern(100, 2),
      Pattern(2 * kLcmFragmentPayload - channel.size() - 1, 3), Pattern(300'000, 4),
      Pattern(3'000'001, 5)};
  std::vector<std::vector<std::uint8_t>> received;
  (*subscriber)->Subscribe(channel, [&](const BusMessage& m) {
    received.emplace_back(m.data.begin(), m.data.end());
  });
  // liblcm starts its receive thread at the first subscription: let it settle.
  (void)(*subscriber)->HandleOnce(50ms);
  for (const auto& message : sent) {
    ASSERT_TRUE((*publisher)->Publish(channel, std::span<const std::uint8_t>(message)).ok());
  }
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (received.size() < sent.size() && std::chrono::steady_clock::now() < end) {
    (void)(*subscriber)->HandleOnce(20ms);
  }
  ASSERT_EQ(received.size(), sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i)
    EXPECT_TRUE(received[i] == sent[i]) << "message " << i;
}

TEST(UdpmSender, PacingIsIgnoredOnOtherProviders) {
  PublishPacing pacing;
  pacing.burst_bytes = 1024;
  pacing.gap = 100us;
  auto bus = OpenLcmBus("memq://", pacing);
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::size_t got = 0;
  (*bus)->Subscribe("M", [&](const BusMessage& m) { got = m.data.size(); });
  const auto message = Pattern(100'000, 9);
  ASSERT_TRUE((*bus)->Publish("M", std::span<const std::uint8_t>(message)).ok());
  ASSERT_TRUE((*bus)->HandleOnce(100ms).ok());
  EXPECT_EQ(got, message.size());
}

}  // namespace
}  // namespace selfcal
