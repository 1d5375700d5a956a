// The receive loop of selfcal-wenglor: connect (retrying), poll, hand profiles on, and reconnect
// after a link loss. Kept apart from main() so that tests run exactly this loop.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

#include "core/util/expected.h"
#include "drivers/wenglor/wenglor_scanner.h"

namespace selfcal::wenglor {

using ProfileSink = std::function<void(const Profile&)>;

// Runs until `stop` becomes true. Connection failures and link losses are logged through the
// scanner's logger and retried every reconnect_interval_ms; they never end the loop.
// `tick`, when given, runs in the loop about every `tick_interval` (for periodic statistics).
void RunScanner(WenglorScanner& scanner, const std::atomic<bool>& stop, const ProfileSink& sink,
                const std::function<void()>& tick = nullptr,
                std::chrono::milliseconds tick_interval = std::chrono::seconds(10));

}  // namespace selfcal::wenglor
