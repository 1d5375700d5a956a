// The drivers' publishing queue on a real LCM bus (memq://) and on a bus that refuses: what it
// publishes, in order; what it drops and fails, counted; Flush and Stop lose nothing queued.
#include "protocols/bus/queued_publisher.h"

#include <gtest/gtest.h>

#include <vector>

#include "selfcal/joint_state_t.hpp"

namespace selfcal {
namespace {

joint_state_t StateAt(std::int64_t utime) {
  joint_state_t message;
  message.utime = utime;
  message.num_joints = 1;
  message.names = {"A1"};
  message.positions = {0.001 * static_cast<double>(utime)};
  message.velocities = {0.0};
  message.efforts = {0.0};
  return message;
}

void Prepare(joint_state_t& slot) { slot.positions.reserve(1); }

TEST(QueuedPublisher, PublishesEveryMessageInOrderOnTheBus) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::vector<std::int64_t> received;
  (*bus)->Subscribe("Q", [&](const BusMessage& m) {
    auto state = DecodeLcm<joint_state_t>(m.data, "Q");
    ASSERT_TRUE(state.ok()) << state.error().message;
    received.push_back(state->utime);
  });
  {
    QueuedPublisher<joint_state_t> queue(**bus, "Q", 64, Prepare);
    for (std::int64_t i = 1; i <= 50; ++i) {
      ASSERT_TRUE(queue.Submit([i](joint_state_t& slot) {
        slot = StateAt(i);
        return true;
      }));
    }
    queue.Flush();
    EXPECT_EQ(queue.stats().published, 50);
    EXPECT_EQ(queue.stats().dropped, 0);
    EXPECT_EQ(queue.stats().failed, 0);
  }
  for (;;) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(0));
    ASSERT_TRUE(handled.ok()) << handled.error().message;
    if (!*handled) break;
  }
  ASSERT_EQ(received.size(), 50u);
  for (std::size_t i = 0; i < received.size(); ++i) {
    EXPECT_EQ(received[i], static_cast<std::int64_t>(i + 1));
  }
}

TEST(QueuedPublisher, DataThatDoesNotFitIsDroppedAndCounted) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  QueuedPublisher<joint_state_t> queue(**bus, "Q", 4, Prepare);
  EXPECT_FALSE(queue.Submit([](joint_state_t&) { return false; }));
  queue.Flush();
  EXPECT_EQ(queue.stats().dropped, 1);
  EXPECT_EQ(queue.stats().published, 0);
}

TEST(QueuedPublisher, ABusThatRefusesIsCountedWithItsReasonAndStopLosesNothingQueued) {
  class RefusingBus final : public Bus {
   public:
    Status Publish(const std::string& channel, std::span<const std::uint8_t>) override {
      return Error{"no route for " + channel};
    }
    void Subscribe(const std::string&, Handler) override {}
    Expected<bool> HandleOnce(std::chrono::milliseconds) override { return false; }
    int FileDescriptor() const override { return -1; }
    const std::string& url() const override { return url_; }

   private:
    std::string url_ = "refusing://";
  } bus;
  QueuedPublisher<joint_state_t> queue(bus, "Q", 8, Prepare);
  int accepted = 0;
  for (std::int64_t i = 0; i < 8; ++i) {
    accepted += queue.Submit([i](joint_state_t& slot) {
      slot = StateAt(i);
      return true;
    });
  }
  queue.Stop();
  const QueueStats stats = queue.stats();
  EXPECT_EQ(stats.failed, accepted);
  EXPECT_EQ(stats.published, 0);
  EXPECT_EQ(stats.failed + stats.dropped, 8);
  EXPECT_EQ(queue.last_error(), "no route for Q");
}

}  // namespace
}  // namespace selfcal
