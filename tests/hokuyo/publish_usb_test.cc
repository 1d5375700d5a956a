// The publishing layer over real LCM (memq://) and libusb discovery. USB devices cannot exist
// here: the no-device and hotplug-armed paths are the ones libusb lets us test (test-peers.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "drivers/hokuyo/publisher.h"
#include "drivers/hokuyo/usb_discovery.h"
#include "protocols/lcm/channels.h"

namespace selfcal::hokuyo {
namespace {

RangeScan DistinctScan(int seed) {
  RangeScan scan;
  scan.utime = 1'700'000'000'000'000 + seed;
  scan.device_utime = 123'456'000 + seed;
  scan.scan_counter = 77 + seed;
  scan.time_per_ray = 1.7361e-5;
  scan.angle_first = -2.356;
  scan.angle_increment = 0.00436;
  scan.ranges = {1.5f, std::nanf(""), 30.0f, static_cast<float>(seed)};
  scan.intensities = {100.0f, 200.0f, 300.0f, 400.0f};
  return scan;
}

TEST(ScanPublisher, PublishesEveryFieldOnTheBus) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::vector<range_scan_t> received;
  (*bus)->Subscribe(channels::kRangeScan, [&](const BusMessage& message) {
    auto decoded = DecodeLcm<range_scan_t>(message.data, message.channel);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;
    received.push_back(*decoded);
  });
  {
    ScanPublisher publisher(**bus, channels::kRangeScan, 4, 8);
    for (int i = 0; i < 3; ++i) publisher.Submit(DistinctScan(i));
    publisher.Flush();
    EXPECT_EQ(publisher.published(), 3);
    EXPECT_EQ(publisher.dropped(), 0);
  }
  while (*(*bus)->HandleOnce(std::chrono::milliseconds(10))) {
  }
  ASSERT_EQ(received.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const RangeScan expected = DistinctScan(i);
    const range_scan_t& m = received[static_cast<std::size_t>(i)];
    EXPECT_EQ(m.utime, expected.utime);
    EXPECT_EQ(m.device_utime, expected.device_utime);
    EXPECT_EQ(m.scan_counter, expected.scan_counter);
    EXPECT_EQ(m.time_per_ray, expected.time_per_ray);
    EXPECT_EQ(m.angle_first, expected.angle_first);
    EXPECT_EQ(m.angle_increment, expected.angle_increment);
    ASSERT_EQ(m.num_ranges, 4);
    EXPECT_EQ(m.ranges[0], 1.5f);
    EXPECT_TRUE(std::isnan(m.ranges[1]));
    EXPECT_EQ(m.ranges[3], static_cast<float>(i));
    ASSERT_EQ(m.num_intensities, 4);
    EXPECT_EQ(m.intensities[2], 300.0f);
  }
}

TEST(ScanPublisher, DropsTheNewestWhenTheQueueIsFullAndNeverBlocks) {
  // A bus that blocks forever on publish would stall the driver: the publisher must not.
  class SlowBus final : public Bus {
   public:
    Status Publish(const std::string&, std::span<const std::uint8_t>) override {
      std::unique_lock<std::mutex> lock(mutex_);
      released_.wait(lock, [this] { return release_; });
      return OkStatus();
    }
    void Subscribe(const std::string&, Handler) override {}
    Expected<bool> HandleOnce(std::chrono::milliseconds) override { return false; }
    int FileDescriptor() const override { return -1; }
    const std::string& url() const override { return url_; }
    void Release() {
      std::lock_guard<std::mutex> lock(mutex_);
      release_ = true;
      released_.notify_all();
    }

   private:
    std::string url_ = "slow://";
    std::mutex mutex_;
    std::condition_variable released_;
    bool release_ = false;
  } bus;
  ScanPublisher publisher(bus, "X", 2, 8);
  for (int i = 0; i < 10; ++i) publisher.Submit(DistinctScan(i));  // returns at once
  EXPECT_GE(publisher.dropped(), 7);                               // one in flight, two queued
  bus.Release();
  publisher.Flush();
  EXPECT_EQ(publisher.published() + publisher.dropped(), 10);
}

TEST(UsbDiscovery, NoHokuyoAttachedIsAnEmptyListNotAnError) {
  const auto devices = ListHokuyoUsb();
  ASSERT_TRUE(devices.ok()) << devices.error().message;
  EXPECT_TRUE(devices->empty()) << "a Hokuyo is attached to this machine?";
}

TEST(UsbDiscovery, HotplugArmsWithoutDevices) {
  std::atomic<int> events{0};
  auto watcher = UsbHotplugWatcher::Start(
      [&](UsbHotplugWatcher::Event, const UsbDevice&) { events.fetch_add(1); });
  if (!watcher.ok()) {
    GTEST_SKIP() << "libusb hotplug unavailable here: " << watcher.error().message;
  }
  EXPECT_TRUE((*watcher)->armed());
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  EXPECT_EQ(events.load(), 0);
  watcher->reset();  // disarms and joins without hanging
}

TEST(UsbDiscovery, MapsAUsbPortToItsTtyThroughSysfs) {
  // A sysfs-shaped tree: the interface 1-2.4:1.0 of a CDC-ACM device owns tty/ttyACM3.
  const auto root =
      std::filesystem::temp_directory_path() / ("selfcal-usb-sysfs-" + std::to_string(getpid()));
  std::filesystem::create_directories(root / "1-2.4:1.0" / "tty" / "ttyACM3");
  std::filesystem::create_directories(root / "1-2.4");
  std::filesystem::create_directories(root / "1-2.5:1.0");
  EXPECT_EQ(TtyForPortPath("1-2.4", root.string()), "/dev/ttyACM3");
  EXPECT_EQ(TtyForPortPath("1-2.5", root.string()), "");
  EXPECT_EQ(TtyForPortPath("1-2", root.string()), "");
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace selfcal::hokuyo
