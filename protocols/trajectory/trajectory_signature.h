// Signed trajectories: a joint_trajectory_t moves the arm and LCM is unauthenticated multicast,
// so the daemon signs every trajectory it sends with its key (protocols/auth/key.h) under the
// trajectory's own domain string, and the arm's driver executes only what TrajectoryVerifier
// accepts: the right tag, within its validity, not seen before.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "protocols/auth/key.h"
#include "selfcal/joint_trajectory_t.hpp"

namespace selfcal {

// The longest validity a driver accepts (valid_until - utime), and how far the sender's clock
// may be ahead of the driver's (a trajectory is refused before utime - kMaxTrajectoryValidityUs).
inline constexpr std::int64_t kMaxTrajectoryValidityUs = 30'000'000;
// The validity the daemon signs with: a trajectory is executed on arrival, this leaves room for
// the bus, a loaded host and clocks a few seconds apart.
inline constexpr std::int64_t kTrajectoryValidityUs = 10'000'000;
// How many signed trajectories a driver remembers against replay (they are a few per session).
inline constexpr std::size_t kTrajectoryReplayCapacity = 1000;

// The bytes the tag covers after the domain string "selfcal.joint_trajectory_t/v1": utime and
// valid_until (8 bytes big-endian each), trajectory_id, num_joints and joint_names, num_points,
// time_from_start, positions and velocities row by row (doubles as their IEEE 754 bits), each
// count 4 bytes big-endian, each string its 4-byte length and its bytes. The counts are the
// arrays' own sizes, so a message whose counts and arrays disagree cannot share a signature with
// one whose agree. Independent of LCM's encoding.
std::vector<std::uint8_t> CanonicalTrajectoryBytes(const selfcal::joint_trajectory_t& message);

// Sets valid_until = utime + `validity_us` and fills tag_length and tag.
void SignTrajectory(selfcal::joint_trajectory_t& message, const auth::Key& key,
                    std::int64_t validity_us = kTrajectoryValidityUs);

// The driver's check of every trajectory that would move the arm (not of stop requests).
class TrajectoryVerifier {
 public:
  // Without a key every trajectory is refused (fail closed). Trajectories signed before
  // `not_before_utime` (the driver's start: what it saw before is forgotten) are refused.
  TrajectoryVerifier(std::optional<auth::Key> key, std::int64_t not_before_utime,
                     std::size_t capacity = kTrajectoryReplayCapacity)
      : key_(key), not_before_utime_(not_before_utime), capacity_(capacity) {}
  // Empty when `message` may be executed, else why not. `now_utime` is wall time (the sender
  // signed wall time); `now_monotonic_us` keeps a remembered tag past a wall-clock step.
  std::string Check(const selfcal::joint_trajectory_t& message, std::int64_t now_utime,
                    std::int64_t now_monotonic_us);
  // Whether the tag is the key's, nothing else (no time, no replay): for logging stop requests.
  bool Authentic(const selfcal::joint_trajectory_t& message) const;

 private:
  struct Seen {
    std::int64_t valid_until;
    std::int64_t received_monotonic_us;
  };
  // Forgets tags that no clock can make valid again: expired by the wall clock and received
  // longer ago than any validity by the monotonic one.
  void Forget(std::int64_t now_utime, std::int64_t now_monotonic_us);

  std::optional<auth::Key> key_;
  std::int64_t not_before_utime_;
  std::size_t capacity_;
  std::unordered_map<std::string, Seen> seen_;  // by tag (its bytes)
};

}  // namespace selfcal
