#include "tools/sim_scip/sim_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pty.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>

#include "core/timing/host_clock.h"

namespace selfcal::sim_scip {
namespace {

constexpr std::size_t kMaxPendingBytes = 1 << 20;  // a host that stops reading loses data

int SpeedToBaud(speed_t speed) {
  switch (speed) {
    case B9600:
      return 9600;
    case B19200:
      return 19200;
    case B38400:
      return 38400;
    case B57600:
      return 57600;
    case B115200:
      return 115200;
    case B230400:
      return 230400;
    case B460800:
      return 460800;
    case B500000:
      return 500000;
    case B921600:
      return 921600;
    case B1000000:
      return 1000000;
    default:
      return static_cast<int>(speed);
  }
}

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

void SetNonBlocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK); }

}  // namespace

// The simulator's truth is expressed in host CLOCK_MONOTONIC [us].
using timing::MonotonicUs;

SimServer::SimServer(SimDeviceConfig device, SimServerOptions options,
                     std::shared_ptr<RangeSource> source)
    : options_(std::move(options)), device_(std::move(device), std::move(source), MonotonicUs()) {}

Expected<std::unique_ptr<SimServer>> SimServer::Start(SimDeviceConfig device,
                                                      SimServerOptions options,
                                                      std::shared_ptr<RangeSource> source) {
  std::unique_ptr<SimServer> server(
      new SimServer(std::move(device), std::move(options), std::move(source)));
  if (pipe2(server->wake_pipe_, O_NONBLOCK | O_CLOEXEC) != 0) return Error{Errno("pipe2")};
  if (auto status = server->OpenEndpoint(); !status) return status.error();
  server->thread_ = std::thread([s = server.get()] { s->Loop(); });
  return server;
}

SimServer::~SimServer() {
  Stop();
  CloseClient();
  CloseEndpoint();
  for (int fd : wake_pipe_) {
    if (fd >= 0) close(fd);
  }
}

void SimServer::Stop() {
  if (stop_.exchange(true)) return;
  Wake();
  if (thread_.joinable()) thread_.join();
}

std::string SimServer::pty_path() const {
  return options_.pty_link.empty() ? pts_path_ : options_.pty_link;
}

Status SimServer::OpenEndpoint() {
  if (options_.transport == SimServerOptions::Transport::kTcp) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (fd < 0) return Error{Errno("socket")};
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port_ ? port_ : options_.port));
    if (inet_pton(AF_INET, options_.address.c_str(), &address.sin_addr) != 1) {
      close(fd);
      return Error{"bad address " + options_.address};
    }
    if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
        listen(fd, 4) != 0) {
      const std::string error = Errno("bind/listen " + options_.address);
      close(fd);
      return Error{error};
    }
    socklen_t length = sizeof(address);
    getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);  // kept: the sensor comes back on the same port
    listen_fd_ = fd;
    return OkStatus();
  }
  int master = -1;
  int slave = -1;
  char name[256] = {};
  if (openpty(&master, &slave, name, nullptr, nullptr) != 0) return Error{Errno("openpty")};
  termios tio{};
  tcgetattr(slave, &tio);
  cfmakeraw(&tio);
  tcsetattr(slave, TCSANOW, &tio);
  SetNonBlocking(master);
  fcntl(master, F_SETFD, FD_CLOEXEC);
  fcntl(slave, F_SETFD, FD_CLOEXEC);
  master_fd_ = master;
  slave_fd_ = slave;
  pts_path_ = name;
  if (!options_.pty_link.empty()) {
    // Replace the link atomically: a driver polling it never sees a half-made one.
    const std::string temporary = options_.pty_link + ".new";
    unlink(temporary.c_str());
    if (symlink(pts_path_.c_str(), temporary.c_str()) != 0 ||
        rename(temporary.c_str(), options_.pty_link.c_str()) != 0) {
      return Error{Errno("symlink " + options_.pty_link)};
    }
  }
  connections_.fetch_add(1);
  return OkStatus();
}

void SimServer::CloseClient() {
  if (client_fd_ >= 0) close(client_fd_);
  client_fd_ = -1;
  pending_out_.clear();
}

void SimServer::CloseEndpoint() {
  if (listen_fd_ >= 0) close(listen_fd_);
  listen_fd_ = -1;
  if (master_fd_ >= 0) {
    if (!options_.pty_link.empty()) unlink(options_.pty_link.c_str());
    close(master_fd_);
    close(slave_fd_);
  }
  master_fd_ = -1;
  slave_fd_ = -1;
  pending_out_.clear();
}

void SimServer::Wake() {
  const char byte = 1;
  if (wake_pipe_[1] >= 0) (void)!write(wake_pipe_[1], &byte, 1);
}

template <typename F>
void SimServer::Post(F&& f) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    posted_.emplace_back(std::forward<F>(f));
  }
  Wake();
}

void SimServer::Disconnect(double down_s) {
  Post([this, down_s] {
    CloseClient();
    CloseEndpoint();
    device_.HostGone();  // the host is gone: the sensor stops streaming
    down_until_us_ = MonotonicUs() + down_s * 1e6;
  });
}

void SimServer::Reboot(double boot_s) {
  Post([this, boot_s] {
    CloseClient();
    CloseEndpoint();
    const double now = MonotonicUs();
    const double back = now + boot_s * 1e6;
    if (device_.answers_while_booting()) {
      device_.PowerCycleAnswering(now, back);
      down_until_us_ = now + 1e3;  // the link is back at once
    } else {
      device_.PowerCycle(back);
      down_until_us_ = back;
    }
  });
}

void SimServer::CorruptNextScans(int count) {
  Post([this, count] { device_.CorruptNextScans(count); });
}

void SimServer::Stall(double seconds) {
  Post([this, seconds] { device_.StallUntil(MonotonicUs() + seconds * 1e6); });
}

void SimServer::InjectJunk(const std::string& bytes) {
  Post([this, bytes] { device_.InjectJunk(bytes, MonotonicUs()); });
}

void SimServer::SetTruthCallback(std::function<void(const ScanTruth&)> callback) {
  Post([this, callback = std::move(callback)] { device_.SetTruthCallback(callback); });
}

void SimServer::Loop() {
  // Send on time: the default 50 us timer slack would delay every reply (a one-sided latency).
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  char buffer[4096];
  std::string out;
  while (!stop_.load()) {
    std::vector<std::function<void()>> posted;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      posted.swap(posted_);
    }
    for (auto& f : posted) f();

    double now = MonotonicUs();
    if (down_until_us_ > 0 && now >= down_until_us_) {
      if (OpenEndpoint().ok()) down_until_us_ = 0;
    }
    device_.Advance(now);
    out.clear();
    device_.TakeDue(now, out);
    const int peer =
        options_.transport == SimServerOptions::Transport::kTcp ? client_fd_ : master_fd_;
    if (peer >= 0 && pending_out_.size() + out.size() <= kMaxPendingBytes) pending_out_ += out;
    if (peer >= 0 && !pending_out_.empty()) {
      const ssize_t n = write(peer, pending_out_.data(), pending_out_.size());
      if (n > 0) pending_out_.erase(0, static_cast<std::size_t>(n));
    }

    double wait_us = std::min(device_.NextEventUs() - now, 50e3);
    if (down_until_us_ > 0) wait_us = std::min(wait_us, down_until_us_ - now);
    if (!pending_out_.empty()) wait_us = std::min(wait_us, 1e3);
    wait_us = std::max(wait_us, 0.0);
    pollfd fds[3];
    nfds_t count = 0;
    fds[count++] = {wake_pipe_[0], POLLIN, 0};
    if (listen_fd_ >= 0) fds[count++] = {listen_fd_, POLLIN, 0};
    if (peer >= 0) fds[count++] = {peer, POLLIN, 0};
    const timespec timeout{static_cast<time_t>(wait_us / 1e6),
                           static_cast<long>(std::fmod(wait_us, 1e6) * 1e3)};
    if (ppoll(fds, count, &timeout, nullptr) <= 0) continue;
    for (nfds_t i = 0; i < count; ++i) {
      if (fds[i].revents == 0) continue;
      if (fds[i].fd == wake_pipe_[0]) {
        while (read(wake_pipe_[0], buffer, sizeof(buffer)) > 0) {
        }
      } else if (fds[i].fd == listen_fd_) {
        const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd >= 0) {
          CloseClient();  // one host at a time, like the sensor
          const int one = 1;
          setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
          client_fd_ = fd;
          connections_.fetch_add(1);
        }
      } else {
        const ssize_t n = read(fds[i].fd, buffer, sizeof(buffer));
        const double at = MonotonicUs();
        if (n > 0) {
          int rate = 0;
          if (slave_fd_ >= 0) {
            termios tio{};
            if (tcgetattr(slave_fd_, &tio) == 0) rate = SpeedToBaud(cfgetospeed(&tio));
          }
          device_.Receive(std::string_view(buffer, static_cast<std::size_t>(n)), at, rate);
        } else if (n == 0 && fds[i].fd == client_fd_) {
          CloseClient();
          device_.HostGone();  // Ethernet sensors stop streaming when the host leaves
        } else if (n < 0 && errno != EAGAIN && errno != EINTR && fds[i].fd == client_fd_) {
          CloseClient();
          device_.HostGone();
        }
      }
    }
  }
}

}  // namespace selfcal::sim_scip
