#include "protocols/trajectory/trajectory_signature.h"

#include <string_view>

namespace selfcal {
namespace {

constexpr std::string_view kDomain = "selfcal.joint_trajectory_t/v1";

}  // namespace

std::vector<std::uint8_t> CanonicalTrajectoryBytes(const selfcal::joint_trajectory_t& message) {
  std::vector<std::uint8_t> out;
  auth::AppendUint(out, static_cast<std::uint64_t>(message.utime), 8);
  auth::AppendUint(out, static_cast<std::uint64_t>(message.valid_until), 8);
  auth::AppendString(out, message.trajectory_id);
  auth::AppendUint(out, message.joint_names.size(), 4);
  for (const std::string& name : message.joint_names) auth::AppendString(out, name);
  auth::AppendUint(out, message.time_from_start.size(), 4);
  for (double t : message.time_from_start) auth::AppendDouble(out, t);
  for (const auto* rows : {&message.positions, &message.velocities}) {
    auth::AppendUint(out, rows->size(), 4);
    for (const std::vector<double>& row : *rows) {
      auth::AppendUint(out, row.size(), 4);
      for (double value : row) auth::AppendDouble(out, value);
    }
  }
  return out;
}

void SignTrajectory(selfcal::joint_trajectory_t& message, const auth::Key& key,
                    std::int64_t validity_us) {
  message.valid_until = message.utime + validity_us;
  message.tag = auth::Tag(key, kDomain, CanonicalTrajectoryBytes(message));
  message.tag_length = static_cast<std::int32_t>(message.tag.size());
}

std::string TrajectoryVerifier::Check(const selfcal::joint_trajectory_t& message,
                                      std::int64_t now_utime, std::int64_t now_monotonic_us) {
  if (!key_) return "no key configured (--key-file): every trajectory is refused";
  if (message.tag_length == 0) return "unsigned trajectory (no tag)";
  // The counts must match the arrays: the tag covers the arrays' own sizes.
  if (message.num_joints != static_cast<std::int32_t>(message.joint_names.size()) ||
      message.num_points != static_cast<std::int32_t>(message.time_from_start.size()) ||
      message.tag_length != static_cast<std::int32_t>(message.tag.size()) ||
      !auth::TagMatches(*key_, kDomain, CanonicalTrajectoryBytes(message), message.tag)) {
    return "wrong signature (tag does not match the key)";
  }
  // Authentic from here on: only the key's holder reaches the replay memory.
  std::int64_t validity = 0, late = 0, early = 0;
  if (__builtin_sub_overflow(message.valid_until, message.utime, &validity) || validity <= 0 ||
      validity > kMaxTrajectoryValidityUs) {
    return "validity outside (0, " + std::to_string(kMaxTrajectoryValidityUs / 1000000) +
           " s] after utime";
  }
  if (__builtin_sub_overflow(now_utime, message.valid_until, &late) || late > 0) {
    return "expired (its valid_until has passed)";
  }
  if (__builtin_sub_overflow(message.utime, now_utime, &early) ||
      early > kMaxTrajectoryValidityUs) {
    return "signed in the future (the sender's clock is ahead)";
  }
  Forget(now_utime, now_monotonic_us);
  if (message.utime < not_before_utime_) {
    return "signed before the driver started (a replay, or the sender's clock is behind)";
  }
  std::string tag(message.tag.begin(), message.tag.end());
  if (seen_.count(tag)) return "replayed (this signed trajectory was received before)";
  if (seen_.size() >= capacity_) {
    return "too many signed trajectories within their validity; refused to stay replay-safe";
  }
  seen_.emplace(std::move(tag), Seen{message.valid_until, now_monotonic_us});
  return {};
}

bool TrajectoryVerifier::Authentic(const selfcal::joint_trajectory_t& message) const {
  return key_ && message.tag_length == static_cast<std::int32_t>(message.tag.size()) &&
         auth::TagMatches(*key_, kDomain, CanonicalTrajectoryBytes(message), message.tag);
}

void TrajectoryVerifier::Forget(std::int64_t now_utime, std::int64_t now_monotonic_us) {
  for (auto it = seen_.begin(); it != seen_.end();) {
    const bool expired = now_utime > it->second.valid_until;
    // Twice the longest validity: the window [utime - max, valid_until] a tag can be valid in.
    const bool old =
        now_monotonic_us - it->second.received_monotonic_us > 2 * kMaxTrajectoryValidityUs;
    it = expired && old ? seen_.erase(it) : std::next(it);
  }
}

}  // namespace selfcal
