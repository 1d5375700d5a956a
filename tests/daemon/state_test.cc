// The daemon's states on the wire: every state survives the round trip, values no daemon sends
// are recognized as such, and the terminal and in-motion states are the documented ones.
#include "daemon/state.h"

#include <gtest/gtest.h>

#include <string>

namespace selfcal::daemon {
namespace {

TEST(StateTest, EveryStateRoundTripsThroughTheWireValue) {
  for (std::int8_t wire = selfcal::calibration_status_t::IDLE;
       wire <= selfcal::calibration_status_t::FAILED; ++wire) {
    const auto state = StateFromWire(wire);
    ASSERT_TRUE(state.has_value()) << int(wire);
    EXPECT_EQ(ToWire(*state), wire);
    EXPECT_STRNE(StateName(*state), "UNKNOWN");
  }
  EXPECT_EQ(StateFromWire(-1), std::nullopt);
  EXPECT_EQ(StateFromWire(10), std::nullopt);
  EXPECT_STREQ(WireStateName(42), "UNKNOWN");
  EXPECT_STREQ(WireStateName(selfcal::calibration_status_t::RECORDING), "RECORDING");
}

TEST(StateTest, TerminalAndMotionStates) {
  for (State s : {State::kAccepted, State::kRejected, State::kAborted, State::kFailed}) {
    EXPECT_TRUE(IsTerminal(s)) << StateName(s);
    EXPECT_FALSE(IsInMotion(s)) << StateName(s);
  }
  for (State s : {State::kIdle, State::kChecking, State::kCalibrating, State::kValidating}) {
    EXPECT_FALSE(IsTerminal(s)) << StateName(s);
    EXPECT_FALSE(IsInMotion(s)) << StateName(s);
  }
  EXPECT_TRUE(IsInMotion(State::kMoving));
  EXPECT_TRUE(IsInMotion(State::kRecording));
}

}  // namespace
}  // namespace selfcal::daemon
