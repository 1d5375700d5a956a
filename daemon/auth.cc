#include "daemon/auth.h"

#include <algorithm>
#include <limits>

namespace selfcal::daemon {
namespace {

constexpr char kDomain[] = "selfcal.calibration_request_t/v2";

}  // namespace

std::vector<std::uint8_t> CanonicalRequestBytes(const selfcal::calibration_request_t& request) {
  std::vector<std::uint8_t> out;
  auth::AppendUint(out, static_cast<std::uint64_t>(request.utime), 8);
  auth::AppendUint(out, static_cast<std::uint8_t>(request.action), 1);
  auth::AppendString(out, request.robot_id);
  auth::AppendString(out, request.nonce);
  auth::AppendString(out, request.plan_name);
  auth::AppendString(out, request.requested_by);
  return out;
}

void SignRequest(selfcal::calibration_request_t& request, const auth::Key& key) {
  request.tag = auth::Tag(key, kDomain, CanonicalRequestBytes(request));
  request.tag_length = static_cast<std::int32_t>(request.tag.size());
}

std::string RandomNonce() { return auth::RandomHex(16); }

const char* VerdictReason(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAccepted:
      return "";
    case Verdict::kUnsigned:
      return "unsigned request (no tag)";
    case Verdict::kBadSignature:
      return "wrong signature (tag does not match the key)";
    case Verdict::kStale:
      return "stale request (utime outside the time window)";
    case Verdict::kReplayed:
      return "replayed request (nonce already used)";
    case Verdict::kMalformed:
      return "malformed request";
    case Verdict::kOtherRobot:
      return "the request is for another robot (robot_id)";
    case Verdict::kTooOld:
      return "signed before the oldest request the daemon remembers (a replay, or the sender's "
             "clock is behind)";
  }
  return "unknown verdict";
}

std::string VerdictText(Verdict verdict) {
  return verdict == Verdict::kAccepted ? "accepted" : RefusedText(VerdictReason(verdict));
}

Verdict RequestAuthenticator::Check(const selfcal::calibration_request_t& request,
                                    std::int64_t now_utime) {
  if (request.nonce.size() > kMaxNonceChars || request.plan_name.size() > kMaxFieldChars ||
      request.requested_by.size() > kMaxFieldChars || request.robot_id.size() > kMaxFieldChars) {
    return Verdict::kMalformed;
  }
  if (request.tag_length == 0) return Verdict::kUnsigned;
  if (request.tag_length != static_cast<std::int32_t>(request.tag.size()) ||
      !auth::TagMatches(key_, kDomain, CanonicalRequestBytes(request), request.tag)) {
    return Verdict::kBadSignature;
  }
  // Only authentic requests reach the checks below, so a forger cannot fill the nonce cache.
  if (request.nonce.empty()) return Verdict::kMalformed;
  if (request.action != selfcal::calibration_request_t::START &&
      request.action != selfcal::calibration_request_t::ABORT &&
      request.action != selfcal::calibration_request_t::ROLLBACK) {
    return Verdict::kMalformed;
  }
  // Authentic, but for another daemon sharing the key: its nonce is not ours to use up.
  if (request.robot_id != robot_id_) return Verdict::kOtherRobot;
  // The sender chose utime: a difference that overflows is as stale as one beyond the window.
  std::int64_t age = 0;
  if (__builtin_sub_overflow(now_utime, request.utime, &age) || age > window_us_ ||
      age < -window_us_) {
    return Verdict::kStale;
  }
  if (request.utime <= refused_up_to_) return Verdict::kTooOld;
  if (seen_.count(request.nonce)) return Verdict::kReplayed;
  RememberNonce(request.nonce, request.utime);
  return Verdict::kAccepted;
}

void RequestAuthenticator::RememberNonce(const std::string& nonce, std::int64_t utime) {
  const auto [remembered, inserted] = seen_.emplace(nonce, utime);
  if (!inserted) return;
  by_utime_.emplace(utime, &remembered->first);
  while (by_utime_.size() > capacity_) {
    const auto [oldest_utime, oldest_nonce] = by_utime_.top();
    RefuseUpTo(oldest_utime);
    by_utime_.pop();
    seen_.erase(seen_.find(*oldest_nonce));
  }
}

void RequestAuthenticator::RefuseUpTo(std::int64_t utime) {
  refused_up_to_ = std::max(refused_up_to_, utime);
}

}  // namespace selfcal::daemon
