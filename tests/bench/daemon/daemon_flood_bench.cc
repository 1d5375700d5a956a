// A flood of forged calibration requests against a running selfcald, with signed probes that
// measure how the daemon keeps up. Run inside a network namespace (daemon_flood_bench.sh starts
// the daemon and the TestArm in one).
//
// While forged requests arrive at --rate per second (wrong key, unsigned, log injection in
// requested_by and the nonce, 60 kB requests, undecodable bytes), the probe:
//   - starts a session and, while it moves, sends one forged request of --big-mib MiB;
//   - waits for that session to end (it must not fail);
//   - while the daemon is idle, sends a signed ABORT every 0.25 s ("nothing to abort");
//   - near the end starts a second session and aborts it with a signed ABORT.
// Every signed request's answer latency is measured; the daemon's RSS, its log and its storage
// (without the session folders the probe's sessions fill) are measured before and after.
// With --signed the flood is of authentic requests instead (a key holder's runaway script):
// signed STARTs of a plan the daemon does not have, refused in every state, each of which must be
// answered; the answers are counted.
// Prints key=value lines; --check exits 1 when a limit of docs/daemon.md's flood test is broken.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "daemon/auth.h"
#include "daemon/clock.h"
#include "daemon/config.h"
#include "daemon/state.h"
#include "protocols/bus/bus.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/calibration_status_t.hpp"

namespace {

namespace fs = std::filesystem;
using Request_t = selfcal::calibration_request_t;
using Status_t = selfcal::calibration_status_t;
using SteadyClock = std::chrono::steady_clock;

double SecondsSince(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

long RssKb(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

// Bytes under `folder`, without the session folders (the probe's own sessions record there).
std::uint64_t StorageBytes(const std::string& folder) {
  std::uint64_t total = 0;
  std::error_code error;
  for (auto it = fs::recursive_directory_iterator(folder, error);
       it != fs::recursive_directory_iterator(); it.increment(error)) {
    if (error) break;
    if (it->path().filename() == "sessions" && it->is_directory()) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file(error)) total += it->file_size(error);
  }
  return total;
}

// The `fraction` quantile of `values` (sorted here); -1 when there are none.
double Quantile(std::vector<double>& values, double fraction) {
  if (values.empty()) return -1;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1));
  return values[index];
}

std::uint64_t FileBytes(const std::string& path) {
  std::error_code error;
  const auto size = fs::file_size(path, error);
  return error ? 0 : size;
}

struct Forger {
  selfcal::auth::Key wrong_key{};
  std::mt19937 random{12345};
  std::uint64_t count = 0;

  std::vector<std::uint8_t> Next(std::int64_t now_utime) {
    ++count;
    if (count % 50 == 0) {  // not a calibration_request_t at all
      std::vector<std::uint8_t> garbage(200);
      for (auto& b : garbage) b = static_cast<std::uint8_t>(random());
      return garbage;
    }
    Request_t request;
    request.utime = now_utime;
    request.action = static_cast<std::int8_t>(1 + count % 3);
    request.nonce = selfcal::daemon::RandomNonce();
    request.plan_name = "";
    request.requested_by = "flood";
    if (count % 10 == 3) {
      request.requested_by = "mallory\n[info] request START by='admin': accepted\x1b[2J";
      request.nonce += "\r\x1b[31m";
    }
    if (count % 100 == 7) request.nonce.assign(60'000, 'n');
    if (count % 10 == 5) {
      request.tag_length = 0;
    } else {
      selfcal::daemon::SignRequest(request, wrong_key);
    }
    return selfcal::EncodeLcm(request);
  }
};

// Authentic requests the daemon must refuse whatever it is doing: START of a plan it lacks.
struct SignedFlood {
  selfcal::auth::Key key{};
  std::string robot_id;
  std::uint64_t count = 0;
  std::mutex mutex;
  // Nonces sent and not yet answered, with the times each was sent.
  struct Sent {
    SteadyClock::time_point time;
    std::int64_t utime;  // the request's, wall time [us]
  };
  std::unordered_map<std::string, Sent> unanswered;
  // Of the answered ones: until the answer was here, and until the daemon stamped it (its utime,
  // the same host's wall clock: without the time the answer waited for this program's loop).
  std::vector<double> latencies_ms, daemon_latencies_ms;
  // Answers slower than 100 ms, counted by the second (since `start`) their request was sent in.
  SteadyClock::time_point start = SteadyClock::now();
  std::map<long, int> slow_by_second;

  std::vector<std::uint8_t> Next(std::int64_t now_utime) {
    ++count;
    Request_t request;
    request.utime = now_utime;
    request.action = Request_t::START;
    request.robot_id = robot_id;
    request.nonce = selfcal::daemon::RandomNonce();
    request.plan_name = "no-such-plan";
    request.requested_by = "runaway-script";
    selfcal::daemon::SignRequest(request, key);
    auto bytes = selfcal::EncodeLcm(request);
    std::lock_guard lock(mutex);
    unanswered.emplace(request.nonce, Sent{SteadyClock::now(), now_utime});
    return bytes;
  }
  // Whether the status answers one of ours, not answered before; its latencies are kept.
  bool Answer(const Status_t& status) {
    const auto now = SteadyClock::now();
    std::lock_guard lock(mutex);
    const auto sent = unanswered.find(status.request_nonce);
    if (sent == unanswered.end()) return false;
    const double latency_ms =
        std::chrono::duration<double, std::milli>(now - sent->second.time).count();
    latencies_ms.push_back(latency_ms);
    daemon_latencies_ms.push_back(static_cast<double>(status.utime - sent->second.utime) / 1e3);
    if (latency_ms > 100) {
      const auto second = std::chrono::duration<double>(sent->second.time - start).count();
      ++slow_by_second[static_cast<long>(second)];
    }
    unanswered.erase(sent);
    return true;
  }
};

struct Probe {
  std::string nonce;
  std::string what;
  SteadyClock::time_point sent;
  std::optional<double> latency_ms;
  std::string answer;
  std::string session_id;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"daemon_flood_bench: forged requests against selfcald, signed probes measured"};
  std::string config_path, key_path, log_path;
  double rate = 1000, seconds = 30, big_mib = 20;
  int daemon_pid = 0;
  bool check = false, signed_flood = false;
  double max_latency_ms = 100, max_rss_growth_mb = 5, max_storage_growth_mb = 1;
  app.add_option("-c,--config", config_path, "The daemon's configuration")->required();
  app.add_option("--key", key_path, "Key file (default: the configuration's)");
  app.add_option("--daemon-pid", daemon_pid, "selfcald's pid, for its RSS")->required();
  app.add_option("--daemon-log", log_path, "selfcald's log file, for its growth");
  app.add_option("--rate", rate, "Forged requests per second");
  app.add_option("--seconds", seconds, "How long the flood lasts");
  app.add_option("--big-mib", big_mib,
                 "Size of the one forged request sent while moving (0: none)");
  app.add_flag("--signed", signed_flood,
               "Flood with signed requests (START of a plan the daemon lacks) instead of forged "
               "ones; each must be answered");
  app.add_flag("--check", check, "Exit 1 when a limit is broken");
  app.add_option("--max-latency-ms", max_latency_ms, "Limit on every signed request's answer");
  app.add_option("--max-rss-growth-mb", max_rss_growth_mb, "Limit on the daemon's RSS growth");
  app.add_option("--max-storage-growth-mb", max_storage_growth_mb,
                 "Limit on the storage's growth (without session folders)");
  CLI11_PARSE(app, argc, argv);

  auto config = selfcal::daemon::ReadDaemonConfig(config_path);
  if (!config) {
    std::cerr << "error: " << config.error().message << "\n";
    return 2;
  }
  auto key = selfcal::auth::ReadKeyFile(key_path.empty() ? config->key_file : key_path, false);
  if (!key) {
    std::cerr << "error: " << key.error().message << "\n";
    return 2;
  }
  auto probe_bus = selfcal::OpenLcmBus(config->lcm_url);
  auto flood_bus = selfcal::OpenLcmBus(config->lcm_url);
  if (!probe_bus || !flood_bus) {
    std::cerr << "error: cannot open LCM at " << config->lcm_url << "\n";
    return 2;
  }
  const std::string& request_channel = config->channels.calibration_request;

  SignedFlood flood_signed;
  flood_signed.key = *key;
  flood_signed.robot_id = config->robot_id;
  std::uint64_t signed_answered = 0;
  std::deque<Probe> probes;  // stable references
  std::optional<Status_t> last_status;
  std::map<std::string, std::string> outcomes;  // session id -> outcome and reason
  // Large queues: under the flood (before the daemon bounds its answers) statuses come at the
  // flood's rate, and liblcm's 30 would drop the ones that matter.
  (*probe_bus)
      ->SubscribeWithQueue(
          config->channels.calibration_result,
          [&](const selfcal::BusMessage& m) {
            auto result = selfcal::DecodeLcm<selfcal::calibration_result_t>(m.data, m.channel);
            if (!result) return;
            using Result_t = selfcal::calibration_result_t;
            const char* outcome = result->outcome == Result_t::ACCEPTED   ? "ACCEPTED"
                                  : result->outcome == Result_t::REJECTED ? "REJECTED"
                                  : result->outcome == Result_t::FAILED   ? "FAILED"
                                  : result->outcome == Result_t::ABORTED  ? "ABORTED"
                                                                          : "UNKNOWN";
            outcomes[result->session_id] = std::string(outcome) + ": " + result->reason;
          },
          10000);
  (*probe_bus)
      ->SubscribeWithQueue(
          config->channels.calibration_status,
          [&](const selfcal::BusMessage& m) {
            auto status = selfcal::DecodeLcm<Status_t>(m.data, m.channel);
            if (!status) return;
            last_status = *status;
            if (status->request_nonce.empty()) return;
            if (signed_flood && flood_signed.Answer(*status)) {
              ++signed_answered;
              return;
            }
            for (auto& probe : probes) {
              if (!probe.latency_ms && probe.nonce == status->request_nonce) {
                probe.latency_ms =
                    std::chrono::duration<double, std::milli>(SteadyClock::now() - probe.sent)
                        .count();
                probe.answer = status->message;
                probe.session_id = status->session_id;
              }
            }
          },
          10000);
  // The daemon's RSS every 5 s from the flood's start: growth that stops is a warm-up, not a leak.
  std::vector<long> rss_samples;
  std::optional<SteadyClock::time_point> next_rss_sample;
  auto handle = [&](double for_seconds) {
    const auto until = SteadyClock::now() + std::chrono::duration<double>(for_seconds);
    while (SteadyClock::now() < until) {
      (void)(*probe_bus)->HandleOnce(std::chrono::milliseconds(5));
      if (next_rss_sample && SteadyClock::now() >= *next_rss_sample) {
        rss_samples.push_back(RssKb(daemon_pid));
        *next_rss_sample += std::chrono::seconds(5);
      }
    }
  };
  auto send = [&](std::int8_t action, const std::string& what) -> Probe& {
    Request_t request;
    request.utime = selfcal::timing::RealtimeUs();
    request.action = action;
    request.robot_id = config->robot_id;
    request.nonce = selfcal::daemon::RandomNonce();
    request.plan_name = "";
    request.requested_by = "daemon_flood_bench";
    selfcal::daemon::SignRequest(request, *key);
    probes.push_back({request.nonce, what, SteadyClock::now(), std::nullopt, "", ""});
    (void)(*probe_bus)->Publish(request_channel, request);
    return probes.back();
  };
  auto state = [&] {
    return last_status ? selfcal::daemon::StateFromWire(last_status->state) : std::nullopt;
  };

  handle(0.5);
  const long rss_before = RssKb(daemon_pid);
  const std::uint64_t storage_before = StorageBytes(config->storage.folder);
  const std::uint64_t log_before = log_path.empty() ? 0 : FileBytes(log_path);

  std::atomic<bool> flooding{true};
  std::uint64_t flood_sent = 0;
  flood_signed.start = SteadyClock::now();
  std::thread flood([&] {
    Forger forger;
    forger.wrong_key.fill(0x5a);
    const auto start = SteadyClock::now();
    while (flooding.load()) {
      const double due = SecondsSince(start) * rate;
      while (static_cast<double>(signed_flood ? flood_signed.count : forger.count) < due) {
        const auto now = selfcal::timing::RealtimeUs();
        const auto bytes = signed_flood ? flood_signed.Next(now) : forger.Next(now);
        if ((*flood_bus)->Publish(request_channel, bytes)) ++flood_sent;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  });

  const auto start = SteadyClock::now();
  next_rss_sample = start;
  // Session 1, with the big forged request while it moves.
  std::string session1_outcome = "not started";
  bool big_sent = false;
  // The daemon's RSS just before the big request and 1.5 s after: liblcm may keep the buffer of
  // a partly received large message (a lost fragment), once, which is not growth under the flood.
  long rss_at_big = -1, rss_after_big = -1;
  SteadyClock::time_point big_time;
  handle(0.5);
  Probe& start1 = send(Request_t::START, "START session 1");
  handle(0.5);
  if (start1.latency_ms && start1.answer.rfind("refused", 0) != 0) {
    session1_outcome = "running";
    while (SecondsSince(start) < seconds + 60 && !outcomes.count(start1.session_id)) {
      handle(0.05);
      const auto now_state = state();
      if (!now_state) continue;
      if (big_mib > 0 && !big_sent && selfcal::daemon::IsInMotion(*now_state)) {
        Request_t big;
        big.utime = selfcal::timing::RealtimeUs();
        big.action = Request_t::ABORT;
        big.nonce.assign(static_cast<std::size_t>(big_mib * 1024 * 1024), 'N');
        big.requested_by = "mallory";
        selfcal::auth::Key wrong{};
        wrong.fill(0x33);
        selfcal::daemon::SignRequest(big, wrong);
        rss_at_big = RssKb(daemon_pid);
        (void)(*probe_bus)->Publish(request_channel, big);
        big_sent = true;
        big_time = SteadyClock::now();
      }
      if (big_sent && rss_after_big < 0 && SecondsSince(big_time) > 1.5) {
        rss_after_big = RssKb(daemon_pid);
      }
    }
    if (outcomes.count(start1.session_id)) session1_outcome = outcomes[start1.session_id];
  }
  const double session1_end = SecondsSince(start);
  // Idle probes, then session 2 aborted in motion.
  while (SecondsSince(start) < seconds - 3) {
    send(Request_t::ABORT, "ABORT while idle");
    handle(0.25);
  }
  std::string session2_outcome = "not started";
  if (SecondsSince(start) < seconds) {
    Probe& start2 = send(Request_t::START, "START session 2");
    handle(1.0);
    if (start2.latency_ms && start2.answer.rfind("refused", 0) != 0) {
      for (int i = 0; i < 40 && !(state() && selfcal::daemon::IsInMotion(*state())); ++i)
        handle(0.05);
      send(Request_t::ABORT, "ABORT session 2");
      handle(1.0);
      session2_outcome =
          outcomes.count(start2.session_id) ? outcomes[start2.session_id] : "no result";
    } else {
      session2_outcome = "START refused: " + start2.answer;
    }
  }
  while (SecondsSince(start) < seconds) handle(0.05);
  flooding = false;
  flood.join();
  handle(1.0);

  const long rss_after = RssKb(daemon_pid);
  const std::uint64_t storage_after = StorageBytes(config->storage.folder);
  const std::uint64_t log_after = log_path.empty() ? 0 : FileBytes(log_path);
  std::vector<double> latencies;
  int unanswered = 0;
  for (const auto& probe : probes) {
    if (probe.latency_ms) {
      latencies.push_back(*probe.latency_ms);
    } else {
      ++unanswered;
      std::printf("# unanswered: %s\n", probe.what.c_str());
    }
  }
  std::sort(latencies.begin(), latencies.end());
  const double median = latencies.empty() ? -1 : latencies[latencies.size() / 2];
  const double worst = latencies.empty() ? -1 : latencies.back();
  const double elapsed = SecondsSince(start);
  const char* flood_kind = signed_flood ? "signed" : "forged";
  std::printf("%s_sent=%llu %s_rate=%.0f seconds=%.1f\n", flood_kind,
              static_cast<unsigned long long>(flood_sent), flood_kind,
              static_cast<double>(flood_sent) / elapsed, elapsed);
  if (signed_flood) {
    std::lock_guard lock(flood_signed.mutex);
    auto& answered = flood_signed.latencies_ms;
    std::printf("signed_flood_answered=%llu signed_flood_unanswered=%zu\n",
                static_cast<unsigned long long>(signed_answered), flood_signed.unanswered.size());
    std::printf(
        "signed_flood_latency_ms_median=%.1f signed_flood_latency_ms_p99=%.1f "
        "signed_flood_latency_ms_max=%.1f\n",
        Quantile(answered, 0.5), Quantile(answered, 0.99), Quantile(answered, 1.0));
    auto& stamped = flood_signed.daemon_latencies_ms;
    std::printf(
        "signed_flood_stamped_ms_median=%.1f signed_flood_stamped_ms_p99=%.1f "
        "signed_flood_stamped_ms_max=%.1f\n",
        Quantile(stamped, 0.5), Quantile(stamped, 0.99), Quantile(stamped, 1.0));
    std::string slow;
    for (const auto& [second, count] : flood_signed.slow_by_second) {
      slow += (slow.empty() ? "" : ",") + std::to_string(second) + ":" + std::to_string(count);
    }
    std::printf("signed_flood_over_100ms_at_s=%s\n", slow.c_str());
  }
  std::printf("probes=%zu answered=%zu unanswered=%d latency_ms_median=%.1f latency_ms_max=%.1f\n",
              probes.size(), latencies.size(), unanswered, median, worst);
  if (big_sent && rss_after_big < 0) rss_after_big = RssKb(daemon_pid);
  const long big_jump = big_sent ? std::max(0L, rss_after_big - rss_at_big) : 0;
  const long flood_growth = rss_after - rss_before - big_jump;
  std::printf(
      "rss_kb_before=%ld rss_kb_after=%ld rss_growth_kb=%ld rss_jump_at_big_request_kb=%ld "
      "rss_growth_without_that_kb=%ld\n",
      rss_before, rss_after, rss_after - rss_before, big_jump, flood_growth);
  std::string samples;
  for (const long kb : rss_samples) samples += (samples.empty() ? "" : ",") + std::to_string(kb);
  std::printf("rss_kb_every_5s=%s\n", samples.c_str());
  std::printf("storage_bytes_before=%llu storage_bytes_after=%llu storage_growth_bytes=%lld\n",
              static_cast<unsigned long long>(storage_before),
              static_cast<unsigned long long>(storage_after),
              static_cast<long long>(storage_after) - static_cast<long long>(storage_before));
  if (!log_path.empty()) {
    std::printf("log_growth_bytes=%lld\n",
                static_cast<long long>(log_after) - static_cast<long long>(log_before));
  }
  std::printf("big_request_sent=%d session1_ended_at_s=%.1f session1='%s'\n", big_sent ? 1 : 0,
              session1_end, session1_outcome.c_str());
  std::printf("session2='%s'\n", session2_outcome.c_str());
  if (!check) return 0;
  std::vector<std::string> broken;
  if (unanswered > 0) broken.push_back("unanswered signed requests");
  if (signed_flood && !flood_signed.unanswered.empty())
    broken.push_back("unanswered requests of the signed flood");
  if (worst > max_latency_ms) broken.push_back("an answer took longer than the limit");
  if (static_cast<double>(flood_growth) > max_rss_growth_mb * 1024)
    broken.push_back("RSS grew too much");
  if (static_cast<double>(storage_after) - static_cast<double>(storage_before) >
      max_storage_growth_mb * 1024 * 1024)
    broken.push_back("storage grew too much");
  if (session1_outcome.find("ACCEPTED") == std::string::npos)
    broken.push_back("session 1 did not end accepted");
  if (session2_outcome.find("ABORTED") == std::string::npos)
    broken.push_back("session 2 was not aborted");
  for (const auto& why : broken) std::printf("BROKEN: %s\n", why.c_str());
  return broken.empty() ? 0 : 1;
}
