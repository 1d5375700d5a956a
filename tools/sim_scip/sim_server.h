// Serves a SimDevice over TCP (127.0.0.1, port 0 allowed) or a pseudo-terminal, on a thread of
// its own, with faults on demand: disconnect (cable pull), reboot, corrupted bytes, stall, junk.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/util/expected.h"
#include "tools/sim_scip/sim_device.h"

namespace selfcal::sim_scip {

struct SimServerOptions {
  enum class Transport { kTcp, kPty };
  Transport transport = Transport::kTcp;
  std::string address = "127.0.0.1";
  int port = 0;  // 0: the kernel picks one (port() tells)
  // PTY: a symlink to the current /dev/pts/N, kept stable across simulated cable pulls the way a
  // udev /dev/serial/by-id link is. Empty: no link (pty_path() is the pts itself).
  std::string pty_link;
};

class SimServer {
 public:
  static Expected<std::unique_ptr<SimServer>> Start(SimDeviceConfig device,
                                                    SimServerOptions options,
                                                    std::shared_ptr<RangeSource> source = {});
  ~SimServer();
  SimServer(const SimServer&) = delete;
  SimServer& operator=(const SimServer&) = delete;

  int port() const { return port_; }
  std::string pty_path() const;  // the link when configured, else /dev/pts/N

  // Faults, callable from any thread.
  void Disconnect(double down_s);  // drop the link; TCP refuses, the pty vanishes, for down_s
  // Drop the link, reset state and clock, back after boot_s (answers_while_booting: the link is
  // back at once and the device denies TM0, BM and scans until then).
  void Reboot(double boot_s);
  void CorruptNextScans(int count);
  void Stall(double seconds);  // hang: no replies, no scans
  void InjectJunk(const std::string& bytes);

  // Called on the server thread for each scan the device sends.
  void SetTruthCallback(std::function<void(const ScanTruth&)> callback);

  int connections() const { return connections_.load(); }
  void Stop();

 private:
  SimServer(SimDeviceConfig device, SimServerOptions options, std::shared_ptr<RangeSource> source);
  Status OpenEndpoint();
  void CloseEndpoint();
  void CloseClient();
  void Loop();
  void Wake();
  template <typename F>
  void Post(F&& f);

  SimServerOptions options_;
  SimDevice device_;
  int listen_fd_ = -1;
  int client_fd_ = -1;
  int master_fd_ = -1;
  int slave_fd_ = -1;  // held open so the master never sees a hangup when the driver closes
  std::string pts_path_;
  int port_ = 0;
  int wake_pipe_[2] = {-1, -1};
  double down_until_us_ = 0;
  bool reboot_pending_ = false;
  std::string pending_out_;
  std::mutex mutex_;
  std::vector<std::function<void()>> posted_;
  std::atomic<bool> stop_{false};
  std::atomic<int> connections_{0};
  std::thread thread_;
};

}  // namespace selfcal::sim_scip
