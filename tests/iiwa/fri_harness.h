// Test harness: the FRI simulator on 127.0.0.1 (its own thread) and the selfcal-iiwa driver
// on a memq:// bus spun by the test thread, plus recorders of what the driver publishes.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drake/lcmt_iiwa_status.hpp"
#include "drivers/iiwa/iiwa_driver.h"
#include "protocols/auth/key.h"
#include "protocols/lcm/channels.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "protocols/model_file/model_file.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"
#include "tests/time_scale.h"
#include "tools/sim_fri/fri_simulator.h"

namespace selfcal::testing {

inline RobotModel IiwaModel() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  auto file =
      ReadModelFile(std::string(dir ? dir : ".") + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_TRUE(file.ok()) << file.error().message;
  return file->model;
}

// The key the harness's driver verifies trajectories with.
inline auth::Key TestKey() {
  return {0x5e, 0x1f, 0xca, 0x11, 0x0b, 0xad, 0xf0, 0x0d, 0x12, 0x34, 0x56,
          0x78, 0x9a, 0xbc, 0xde, 0xf0, 0x01, 0x23, 0x45, 0x67, 0x89, 0xab,
          0xcd, 0xef, 0xfe, 0xdc, 0xba, 0x98, 0x76, 0x54, 0x32, 0x10};
}

class FriHarness {
 public:
  explicit FriHarness(sim::FriSimOptions sim_options = {}, iiwa::DriverOptions driver_options = {},
                      std::optional<auth::Key> key = TestKey()) {
    const RobotModel model = IiwaModel();
    auto bus = OpenLcmBus("memq://");
    EXPECT_TRUE(bus.ok());
    bus_ = std::move(*bus);
    driver_options.model = model;
    driver_options.key = key;
    driver_options.bind_host = "127.0.0.1";
    driver_options.fri_port = 0;
    auto driver = iiwa::IiwaDriver::Create(driver_options, *bus_);
    EXPECT_TRUE(driver.ok()) << driver.error().message;
    driver_ = std::move(*driver);
    sim_options.model = model;
    sim_options.client_host = "127.0.0.1";
    sim_options.client_port = driver_->port();
    if (sim_options.initial_position.size() == 0) {
      sim_options.initial_position = Eigen::VectorXd::Zero(7);
      sim_options.initial_position << 0.1, 0.4, -0.1, -1.2, 0.2, 0.7, 0.3;
    }
    auto simulator = sim::FriSimulator::Create(sim_options);
    EXPECT_TRUE(simulator.ok()) << simulator.error().message;
    sim_ = std::move(*simulator);
    bus_->Subscribe(channels::kJointState, [this](const BusMessage& m) {
      auto decoded = DecodeLcm<selfcal::joint_state_t>(m.data, m.channel);
      ASSERT_TRUE(decoded.ok()) << decoded.error().message;
      joint_states.push_back(*decoded);
    });
    bus_->Subscribe(channels::kIiwaStatus, [this](const BusMessage& m) {
      iiwa_status_bytes.emplace_back(m.data.begin(), m.data.end());
    });
    bus_->Subscribe(channels::kRobotStatus, [this](const BusMessage& m) {
      auto decoded = DecodeLcm<selfcal::robot_driver_status_t>(m.data, m.channel);
      ASSERT_TRUE(decoded.ok()) << decoded.error().message;
      statuses.push_back(*decoded);
    });
  }
  ~FriHarness() { sim_->Stop(); }

  void Start() { sim_->Start(); }

  // Spins the driver until `done` or `timeout_s`; returns whether `done` became true.
  bool SpinUntil(const std::function<bool()>& done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      auto s = driver_->SpinOnce(std::chrono::milliseconds(1));
      EXPECT_TRUE(s.ok());
      if (done()) return true;
    }
    return done();
  }
  void SpinFor(double seconds) {
    SpinUntil([] { return false; }, seconds);
  }
  bool WaitForState(fri::SessionState state, double timeout_s = 5.0) {
    return SpinUntil([&] { return driver_->session().session_state() == static_cast<int>(state); },
                     ScaledSeconds(timeout_s));
  }
  // Index of the first status with `event` (and `id` if given) after `from`, or -1.
  int FindEvent(std::int8_t event, const std::string& id = "", std::size_t from = 0) const {
    for (std::size_t i = from; i < statuses.size(); ++i) {
      if (statuses[i].event == event && (id.empty() || statuses[i].trajectory_id == id)) {
        return static_cast<int>(i);
      }
    }
    return -1;
  }
  bool WaitForEvent(std::int8_t event, const std::string& id, double timeout_s,
                    std::size_t from = 0) {
    return SpinUntil([&] { return FindEvent(event, id, from) >= 0; }, ScaledSeconds(timeout_s));
  }

  Bus& bus() { return *bus_; }
  iiwa::IiwaDriver& driver() { return *driver_; }
  sim::FriSimulator& sim() { return *sim_; }

  std::vector<selfcal::joint_state_t> joint_states;
  std::vector<std::vector<std::uint8_t>> iiwa_status_bytes;
  std::vector<selfcal::robot_driver_status_t> statuses;

 private:
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<iiwa::IiwaDriver> driver_;
  std::unique_ptr<sim::FriSimulator> sim_;
};

}  // namespace selfcal::testing
