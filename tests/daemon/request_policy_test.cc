// The request policy: an authentic request is acted on only when the daemon's situation allows
// it, and every refusal has its code and its words.
#include "daemon/request_policy.h"

#include <gtest/gtest.h>

namespace selfcal::daemon {
namespace {

using Request_t = selfcal::calibration_request_t;

Request_t Request(std::int8_t action, const std::string& plan = "") {
  Request_t request;
  request.action = action;
  request.plan_name = plan;
  return request;
}

const std::map<std::string, std::string> kPlans = {{"smoke", "smoke.yaml"}, {"demo", "demo.yaml"}};

TEST(RequestPolicyTest, AnIdleDaemonStartsTheRequestedOrTheDefaultPlan) {
  const Situation idle;
  auto named =
      DecideRequest(Verdict::kAccepted, Request(Request_t::START, "demo"), idle, "smoke", kPlans);
  EXPECT_TRUE(named.accepted());
  EXPECT_TRUE(named.authentic());
  EXPECT_EQ(named.plan, "demo");
  EXPECT_EQ(named.text(), "accepted");
  auto fallback =
      DecideRequest(Verdict::kAccepted, Request(Request_t::START), idle, "smoke", kPlans);
  EXPECT_EQ(fallback.plan, "smoke");
  auto unknown =
      DecideRequest(Verdict::kAccepted, Request(Request_t::START, "nope"), idle, "smoke", kPlans);
  EXPECT_EQ(unknown.refusal, Refusal::kUnknownPlan);
  EXPECT_TRUE(unknown.authentic()) << "an authentic request uses its nonce even when refused";
  EXPECT_EQ(unknown.text(), "refused: unknown plan 'nope'");
}

TEST(RequestPolicyTest, VerdictsBecomeRefusalsThatUseNoNonce) {
  for (Verdict verdict :
       {Verdict::kUnsigned, Verdict::kBadSignature, Verdict::kStale, Verdict::kReplayed,
        Verdict::kMalformed, Verdict::kTooOld, Verdict::kOtherRobot}) {
    auto decision = DecideRequest(verdict, Request(Request_t::START), {}, "smoke", kPlans);
    EXPECT_FALSE(decision.accepted()) << VerdictText(verdict);
    EXPECT_EQ(decision.verdict, verdict);
    EXPECT_FALSE(decision.authentic());
    EXPECT_EQ(decision.text(), VerdictText(verdict));
  }
  auto malformed = MalformedRequest("truncated");
  EXPECT_FALSE(malformed.accepted());
  EXPECT_EQ(malformed.verdict, Verdict::kMalformed);
  EXPECT_EQ(malformed.text(), "refused: malformed request (truncated)");
}

TEST(RequestPolicyTest, BusyRefusesStartAndRollbackButNotAbort) {
  const Situation moving{State::kMoving, "S1", false};
  for (std::int8_t action : {Request_t::START, Request_t::ROLLBACK}) {
    auto busy = DecideRequest(Verdict::kAccepted, Request(action), moving, "smoke", kPlans);
    EXPECT_EQ(busy.refusal, Refusal::kBusy) << ActionName(action);
    EXPECT_EQ(busy.text(), "refused: busy (MOVING session S1)");
  }
  EXPECT_TRUE(DecideRequest(Verdict::kAccepted, Request(Request_t::ABORT), moving, "smoke", kPlans)
                  .accepted());
  // Idle, but an aborted computation has not returned yet.
  const Situation stopping{State::kIdle, "S1", true};
  auto busy =
      DecideRequest(Verdict::kAccepted, Request(Request_t::START), stopping, "smoke", kPlans);
  EXPECT_EQ(busy.refusal, Refusal::kBusy);
  EXPECT_EQ(busy.text(), "refused: busy (IDLE, previous computation still stopping)");
  auto nothing =
      DecideRequest(Verdict::kAccepted, Request(Request_t::ABORT), Situation{}, "smoke", kPlans);
  EXPECT_EQ(nothing.refusal, Refusal::kNothingToAbort);
  EXPECT_EQ(nothing.text(), "refused: nothing to abort (idle)");
}

}  // namespace
}  // namespace selfcal::daemon
