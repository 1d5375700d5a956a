// The simulator speaks SCIP 2.0 byte for byte as protocols.md shows: the PP reply of the
// UTM-30LX-EW, status codes and their checksums, TM1, MD acknowledgement and countdown echoes.
// SimDevice is driven with a virtual clock here, so every byte and instant is deterministic.
#include "tools/sim_scip/sim_device.h"

#include <gtest/gtest.h>

#include <string>

#include "protocols/scip/block.h"
#include "protocols/scip/replies.h"

namespace selfcal::sim_scip {
namespace {

// Feeds `command` at `now` and returns everything the device sent within 30 ms.
std::string Exchange(SimDevice& device, const std::string& command, double& now) {
  device.Receive(command, now);
  std::string out;
  const double until = now + 30e3;
  while (true) {
    const double next = device.NextEventUs();
    if (next > until) break;
    now = std::max(now, next);
    device.Advance(now);
    device.TakeDue(now, out);
  }
  now = until;
  return out;
}

SimDeviceConfig Quiet() {
  SimDeviceConfig config;
  config.latency_us = 0;
  return config;
}

TEST(SimDevice, ParametersReplyIsTheCapturedOne) {
  SimDevice device(Quiet(), nullptr, 0);
  double now = 1000;
  EXPECT_EQ(Exchange(device, "PP\n", now),
            "PP\n00P\nMODL:UTM-30LX-EW;I\nDMIN:23;7\nDMAX:60000;J\nARES:1440;^\nAMIN:0;?\n"
            "AMAX:1080;Z\nAFRT:540;0\nSCAN:2400;U\n\n");
}

TEST(SimDevice, VersionAndStatusDecode) {
  SimDevice device(Quiet(), nullptr, 0);
  double now = 1000;
  const auto vv = scip::ParseBlock(Exchange(device, "VV\n", now));
  ASSERT_TRUE(vv.ok()) << vv.error().message;
  const auto version = scip::DecodeVersion(*vv);
  ASSERT_TRUE(version.ok());
  EXPECT_EQ(version->vendor, "Hokuyo Automatic Co.,Ltd.");
  EXPECT_EQ(version->protocol, "SCIP 2.0");
  const auto ii = scip::ParseBlock(Exchange(device, "II\n", now));
  ASSERT_TRUE(ii.ok()) << ii.error().message;
  const auto info = scip::DecodeInfo(*ii);
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->at("LASR"), "OFF");
  EXPECT_EQ(info->at("MODL"), "UTM-30LX-EW");
}

TEST(SimDevice, StatusCodesAsTheSpecifiesThem) {
  SimDevice device(Quiet(), nullptr, 0);
  double now = 1000;
  EXPECT_EQ(Exchange(device, "GD0000108001\n", now), "GD0000108001\n10Q\n\n");  // laser off
  EXPECT_EQ(Exchange(device, "BM\n", now), "BM\n00P\n\n");
  EXPECT_EQ(Exchange(device, "BM\n", now), "BM\n02R\n\n");  // the capture of protocols.md
  EXPECT_EQ(Exchange(device, "XY\n", now), "XY\n0Ee\n\n");
  EXPECT_EQ(Exchange(device, "MD00001080\n", now), "MD00001080\n0Cc\n\n");
  EXPECT_EQ(Exchange(device, "VVx\n", now), "VVx\n0Dd\n\n");
  EXPECT_EQ(Exchange(device, "VV;12345678901234567\n", now), "VV;12345678901234567\n0Dd\n\n");
  EXPECT_EQ(Exchange(device, "MD0000200001000\n", now), "MD0000200001000\n04T\n\n");
  EXPECT_EQ(Exchange(device, "MD0100005001000\n", now), "MD0100005001000\n05U\n\n");
  EXPECT_EQ(Exchange(device, "MDx000108001000\n", now), "MDx000108001000\n01Q\n\n");
  EXPECT_EQ(Exchange(device, "QT\n", now), "QT\n00P\n\n");
  EXPECT_EQ(Exchange(device, "TM0\n", now), "TM0\n00P\n\n");
  EXPECT_EQ(Exchange(device, "TM0\n", now), "TM0\n02R\n\n");
  EXPECT_EQ(Exchange(device, "MD0000108001000\n", now), "MD0000108001000\n0Ee\n\n");
  EXPECT_EQ(Exchange(device, "TM2\n", now), "TM2\n00P\n\n");
  EXPECT_EQ(Exchange(device, "TM2\n", now), "TM2\n03S\n\n");
  EXPECT_EQ(Exchange(device, "VV;tag1\n", now).substr(0, 12), "VV;tag1\n00P\n");
  EXPECT_EQ(Exchange(device, "SS115200\n", now), "SS115200\n00P\n\n");  // USB: accepted
  EXPECT_EQ(Exchange(device, "SS123456\n", now), "SS123456\n02R\n\n");
}

TEST(SimDevice, TimeFollowsTheDriftingClock) {
  SimDeviceConfig config = Quiet();
  config.clock_drift_ppm = 100;
  config.clock_offset_ms = 16000000 - 10;
  SimDevice device(config, nullptr, 0);
  double now = 10.0005e6;  // after power-on: 10.0005 s * (1 + 100 ppm) = 10001.5 ms
  const std::string reply = Exchange(device, "TM1\n", now);
  const auto block = scip::ParseBlock(reply);
  ASSERT_TRUE(block.ok()) << block.error().message;
  const auto time = scip::DecodeTime(*block);
  ASSERT_TRUE(time.ok());
  EXPECT_EQ(*time, 16000000u - 10 + 10001);
  // The spec's example value encodes as in protocols.md: TM1\n00P\nm2@0?\n\n.
  SimDeviceConfig exact = Quiet();
  exact.clock_offset_ms = 16000000;
  SimDevice at_16e6(exact, nullptr, 0);
  double t0 = 0;
  EXPECT_EQ(Exchange(at_16e6, "TM1\n", t0), "TM1\n00P\nm2@0?\n\n");
}

TEST(SimDevice, StreamsWithCountdownEchoesAndExactTiming) {
  SimDeviceConfig config = Quiet();
  config.motor_speed_error = 0;
  std::vector<ScanTruth> truths;
  SimDevice device(config, nullptr, 0);
  device.SetTruthCallback([&](const ScanTruth& t) { truths.push_back(t); });
  double now = 1000;
  std::string bytes = Exchange(device, "MD0000002901002\n", now);
  for (int i = 0; i < 4; ++i) {
    device.Advance(now + 30e3);
    device.TakeDue(now + 30e3, bytes);
    now += 30e3;
  }
  scip::BlockFramer framer;
  framer.Append(bytes);
  std::vector<std::string> echoes;
  while (auto block = framer.Next()) {
    ASSERT_TRUE(block->ok()) << block->error().message;
    echoes.push_back((*block)->echo + " " + (*block)->status);
    if ((*block)->status == "99") {
      ASSERT_EQ((*block)->lines.size(), 3u);  // timestamp, 64 + 26 characters
      EXPECT_EQ((*block)->lines[1].size(), 64u);
      EXPECT_EQ((*block)->lines[2].size(), 26u);
    }
  }
  EXPECT_EQ(echoes, (std::vector<std::string>{"MD0000002901002 00", "MD0000002901001 99",
                                              "MD0000002901000 99"}));
  ASSERT_EQ(truths.size(), 2u);
  EXPECT_NEAR(truths[1].timing.host_time_us - truths[0].timing.host_time_us, 25000, 1e-6);
  EXPECT_EQ(truths[0].timing.timestamp_ms,
            static_cast<std::uint32_t>(std::floor(truths[0].timing.device_time_us / 1000)));
  EXPECT_FALSE(device.streaming());
}

TEST(SimDevice, Rs232ListensAtItsRateOnly) {
  SimDeviceConfig config = Quiet();
  config.serial_baud = 19200;
  SimDevice device(config, nullptr, 0);
  double now = 1000;
  device.Receive("QT\n", now, 115200);  // garbage at the wrong rate
  std::string out;
  device.Advance(now + 1e4);
  device.TakeDue(now + 1e4, out);
  EXPECT_EQ(out, "");
  now += 1e4;
  auto at_rate = [&](const std::string& command, int rate) {
    device.Receive(command, now, rate);
    std::string reply;
    now += 1e4;
    device.Advance(now);
    device.TakeDue(now, reply);
    return reply;
  };
  EXPECT_EQ(at_rate("QT\n", 19200), "QT\n00P\n\n");
  EXPECT_EQ(at_rate("SS115200\n", 19200), "SS115200\n00P\n\n");
  EXPECT_EQ(at_rate("QT\n", 19200), "");
  EXPECT_EQ(at_rate("QT\n", 115200), "QT\n00P\n\n");
  EXPECT_EQ(at_rate("SS115200\n", 115200), "SS115200\n03S\n\n");
}

}  // namespace
}  // namespace selfcal::sim_scip
