// The counter unwrapper with the counters our devices have: the Wenglor's 16-bit picture counter
// (a restart continues the count), the Hokuyo's 24-bit millisecond clock (timestamps read out of
// order step back), GigE Vision 1 block ids (16 bits without 0), CANopen SYNC counters (1 .. N,
// forward only).
#include "core/timing/counter_unwrapper.h"

#include <gtest/gtest.h>

namespace selfcal::timing {
namespace {

using Backwards = CounterOptions::Backwards;

TEST(CounterUnwrapper, ConsecutiveWrapGapRepeatRestart) {
  CounterUnwrapper counter(CounterOptions::Bits(16, Backwards::kRestart));
  auto step = counter.Update(65533);
  EXPECT_EQ(step.unwrapped, 65533);
  EXPECT_EQ(step.lost, 0);
  EXPECT_EQ(step.kind, CounterStepKind::kFirst);
  step = counter.Update(65534);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(65535);
  step = counter.Update(0);  // wrap
  EXPECT_EQ(step.unwrapped, 65536);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(1);
  EXPECT_EQ(step.unwrapped, 65537);
  step = counter.Update(6);  // 4 lost
  EXPECT_EQ(step.lost, 4);
  EXPECT_EQ(step.unwrapped, 65542);
  step = counter.Update(6);
  EXPECT_TRUE(step.repeated());
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(65530);  // more than half the range ahead: read as going backwards
  EXPECT_TRUE(step.went_backwards());
  EXPECT_EQ(step.lost, 0);
  EXPECT_EQ(step.unwrapped, 65543);
  step = counter.Update(3);  // 65531 .. 2 lost across the wrap: 8 lost
  EXPECT_EQ(step.lost, 8);
  counter.Reset();
  step = counter.Update(100);
  EXPECT_EQ(step.unwrapped, 100);
  EXPECT_EQ(step.lost, 0);
}

TEST(CounterUnwrapper, TimestampsFollowBackwardStepsAcrossTheWrap) {
  constexpr std::int64_t kWrap = std::int64_t{1} << 24;  // the Hokuyo's ms clock: 4.66 h
  CounterUnwrapper clock(CounterOptions::Bits(24, Backwards::kFollow));
  EXPECT_EQ(clock.Update(kWrap - 20).unwrapped, kWrap - 20);
  EXPECT_EQ(clock.Update(kWrap - 5).unwrapped, kWrap - 5);
  EXPECT_EQ(clock.Update(3).unwrapped, kWrap + 3);  // wrapped
  // A scan timestamp older than the last TM1 reading: a small step back, not a wrap.
  const CounterStep back = clock.Update(kWrap - 2);
  EXPECT_TRUE(back.went_backwards());
  EXPECT_EQ(back.advance, -5);
  EXPECT_EQ(back.unwrapped, kWrap - 2);
  EXPECT_EQ(clock.Update(10).unwrapped, kWrap + 10);
  EXPECT_EQ(clock.Update(10 + (kWrap / 2)).unwrapped, kWrap + 10 + kWrap / 2);  // half: forward
}

TEST(CounterUnwrapper, BlockIdsThatSkipZero) {
  CounterOptions options;
  options.modulus = 0xFFFF;  // 1 .. 65535
  options.first_value = 1;
  CounterUnwrapper ids(options);
  EXPECT_EQ(ids.Update(65534).unwrapped, 65534);
  EXPECT_EQ(ids.Update(65535).advance, 1);
  const CounterStep wrapped = ids.Update(1);  // 65535 is followed by 1
  EXPECT_EQ(wrapped.advance, 1);
  EXPECT_EQ(wrapped.lost, 0);
  EXPECT_EQ(wrapped.unwrapped, 65536);
  const CounterStep gap = ids.Update(4);
  EXPECT_EQ(gap.lost, 2);
  EXPECT_EQ(gap.unwrapped, 65539);
}

TEST(CounterUnwrapper, LateMessagesAreReportedAndLeaveTheNewestAsReference) {
  // FRI's 32-bit sequence counter over UDP: a datagram may overtake another.
  CounterUnwrapper sequence(CounterOptions::Bits(32, Backwards::kIgnore));
  sequence.Update(0xFFFFFFFE);
  const CounterStep gap = sequence.Update(1);  // 0xFFFFFFFF and 0 lost, across the wrap
  EXPECT_EQ(gap.lost, 2);
  EXPECT_EQ(gap.unwrapped, 0x100000001);
  const CounterStep late = sequence.Update(0);  // one of the lost ones arrives late
  EXPECT_TRUE(late.went_backwards());
  EXPECT_EQ(late.advance, 0);
  EXPECT_EQ(late.unwrapped, 0x100000001);
  EXPECT_TRUE(sequence.Update(1).repeated());
  const CounterStep next = sequence.Update(2);  // counted from the newest, not from the late one
  EXPECT_EQ(next.lost, 0);
  EXPECT_EQ(next.unwrapped, 0x100000002);
}

TEST(CounterUnwrapper, ForwardOnlyCountersReadEveryStepForward) {
  CounterOptions options;
  options.modulus = 10;  // a SYNC counter overflowing at 10: 1 .. 10, then 1 again
  options.first_value = 1;
  options.backwards = Backwards::kNever;
  CounterUnwrapper sync(options);
  EXPECT_EQ(sync.Update(9).kind, CounterStepKind::kFirst);
  EXPECT_EQ(sync.Update(10).advance, 1);
  EXPECT_EQ(sync.Update(1).advance, 1);    // wrapped
  const CounterStep far = sync.Update(9);  // 7 missed: more than half the range, still forward
  EXPECT_EQ(far.kind, CounterStepKind::kForward);
  EXPECT_EQ(far.advance, 8);
  EXPECT_EQ(far.lost, 7);
  const CounterStep turn = sync.Update(9);  // the same value: a whole turn
  EXPECT_EQ(turn.kind, CounterStepKind::kForward);
  EXPECT_EQ(turn.advance, 10);
  EXPECT_EQ(turn.unwrapped, 9 + 1 + 1 + 8 + 10);
}

}  // namespace
}  // namespace selfcal::timing
