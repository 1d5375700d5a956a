// LD_PRELOAD shim: CAN_RAW sockets become AF_UNIX datagram sockets on a shared "bus", so
// unmodified SocketCAN programs (our driver, can-utils' cansend and candump) talk to each other
// on a kernel without AF_CAN (../shared/test-peers.md). Test equipment only, never installed.
//
// Each shim socket binds the abstract address "\0selfcal-canshim/<ifname>/<slot>" (slot 0..63).
// Abstract addresses belong to the network namespace: run every participant inside one
// `unshare -rn` so that tests never collide. A frame written to a socket goes to every other
// slot of its interface (as SocketCAN loops frames back to the other sockets of the host, not to
// the sender). Interfaces: the names in SELFCAL_CANSHIM_INTERFACES (comma-separated; default
// "vcan0,vcan1,can0,can1") get index 4000 + position. Filters and socket options of SOL_CAN_RAW
// are accepted and ignored: every socket sees every frame.
#include <dlfcn.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace {

constexpr int kSlots = 64;
constexpr int kMaxFd = 4096;
constexpr int kIndexBase = 4000;

struct ShimSocket {
  bool is_can = false;
  int slot = -1;
  int ifindex = 0;
  char ifname[IFNAMSIZ] = {};
};

ShimSocket sockets[kMaxFd];
std::mutex mutex;

template <typename F>
F Next(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

// Calls `visit(index, name, length)` for the configured interface names, in order, until it
// returns true; returns whether one did.
template <typename Visit>
bool FindInterface(Visit visit) {
  const char* list = std::getenv("SELFCAL_CANSHIM_INTERFACES");
  if (!list) list = "vcan0,vcan1,can0,can1";
  int position = 0;
  for (const char* start = list; *start; ++position) {
    const char* end = std::strchr(start, ',');
    const std::size_t length = end ? static_cast<std::size_t>(end - start) : std::strlen(start);
    if (visit(kIndexBase + position, start, length)) return true;
    if (!end) break;
    start = end + 1;
  }
  return false;
}

int InterfaceIndex(const char* name) {
  int found = 0;
  FindInterface([&](int index, const char* start, std::size_t length) {
    if (length != std::strlen(name) || std::strncmp(start, name, length) != 0) return false;
    found = index;
    return true;
  });
  return found;
}

bool InterfaceName(int index, char* out) {
  return FindInterface([&](int at, const char* start, std::size_t length) {
    if (at != index || length >= IFNAMSIZ) return false;
    std::memcpy(out, start, length);
    out[length] = 0;
    return true;
  });
}

socklen_t SlotAddress(const char* ifname, int slot, sockaddr_un& address) {
  std::memset(&address, 0, sizeof(address));
  address.sun_family = AF_UNIX;
  const int n = std::snprintf(address.sun_path + 1, sizeof(address.sun_path) - 1,
                              "selfcal-canshim/%s/%d", ifname, slot);
  return static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + static_cast<std::size_t>(n));
}

bool IsCan(int fd) { return fd >= 0 && fd < kMaxFd && sockets[fd].is_can; }

// Sends one frame to every other slot of the socket's interface.
ssize_t Broadcast(int fd, const void* data, std::size_t length) {
  static auto real_sendto =
      Next<ssize_t (*)(int, const void*, size_t, int, const sockaddr*, socklen_t)>("sendto");
  ShimSocket s;
  {
    std::lock_guard lock(mutex);
    s = sockets[fd];
  }
  if (s.slot < 0) {
    errno = EDESTADDRREQ;  // a CAN_RAW socket must be bound before sending
    return -1;
  }
  for (int slot = 0; slot < kSlots; ++slot) {
    if (slot == s.slot) continue;
    sockaddr_un address;
    const socklen_t size = SlotAddress(s.ifname, slot, address);
    real_sendto(fd, data, length, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&address), size);
  }
  return static_cast<ssize_t>(length);
}

}  // namespace

extern "C" {

int socket(int domain, int type, int protocol) {
  static auto real = Next<int (*)(int, int, int)>("socket");
  if (domain == PF_CAN && (type & 0xf) == SOCK_RAW && protocol == CAN_RAW) {
    const int fd = real(AF_UNIX, SOCK_DGRAM | (type & ~0xf), 0);
    if (fd >= 0 && fd < kMaxFd) {
      std::lock_guard lock(mutex);
      sockets[fd] = ShimSocket{};
      sockets[fd].is_can = true;
    }
    return fd;
  }
  return real(domain, type, protocol);
}

int bind(int fd, const sockaddr* address, socklen_t length) {
  static auto real = Next<int (*)(int, const sockaddr*, socklen_t)>("bind");
  if (!IsCan(fd)) return real(fd, address, length);
  const auto* can = reinterpret_cast<const sockaddr_can*>(address);
  char ifname[IFNAMSIZ];
  if (length < sizeof(sockaddr_can) || can->can_family != AF_CAN ||
      !InterfaceName(can->can_ifindex, ifname)) {
    errno = ENODEV;
    return -1;
  }
  for (int slot = 0; slot < kSlots; ++slot) {
    sockaddr_un unix_address;
    const socklen_t size = SlotAddress(ifname, slot, unix_address);
    if (real(fd, reinterpret_cast<sockaddr*>(&unix_address), size) == 0) {
      std::lock_guard lock(mutex);
      sockets[fd].slot = slot;
      sockets[fd].ifindex = can->can_ifindex;
      std::memcpy(sockets[fd].ifname, ifname, IFNAMSIZ);
      return 0;
    }
    if (errno != EADDRINUSE) return -1;
  }
  errno = EADDRINUSE;
  return -1;
}

int close(int fd) {
  static auto real = Next<int (*)(int)>("close");
  if (fd >= 0 && fd < kMaxFd) {
    std::lock_guard lock(mutex);
    sockets[fd] = ShimSocket{};
  }
  return real(fd);
}

int ioctl(int fd, unsigned long request, ...) {
  static auto real = Next<int (*)(int, unsigned long, void*)>("ioctl");
  va_list args;
  va_start(args, request);
  void* argument = va_arg(args, void*);
  va_end(args);
  if (IsCan(fd)) {
    auto* ifr = static_cast<ifreq*>(argument);
    if (request == SIOCGIFINDEX) {
      const int index = InterfaceIndex(ifr->ifr_name);
      if (index == 0) {
        errno = ENODEV;
        return -1;
      }
      ifr->ifr_ifindex = index;
      return 0;
    }
    if (request == SIOCGIFNAME) {
      if (!InterfaceName(ifr->ifr_ifindex, ifr->ifr_name)) {
        errno = ENODEV;
        return -1;
      }
      return 0;
    }
    if (request == SIOCGIFMTU) {
      ifr->ifr_mtu = CAN_MTU;  // classic CAN only
      return 0;
    }
  }
  return real(fd, request, argument);
}

unsigned int if_nametoindex(const char* name) {
  static auto real = Next<unsigned int (*)(const char*)>("if_nametoindex");
  const int index = InterfaceIndex(name);
  return index != 0 ? static_cast<unsigned int>(index) : real(name);
}

char* if_indextoname(unsigned int index, char* name) {
  static auto real = Next<char* (*)(unsigned int, char*)>("if_indextoname");
  if (InterfaceName(static_cast<int>(index), name)) return name;
  return real(index, name);
}

int setsockopt(int fd, int level, int name, const void* value, socklen_t length) {
  static auto real = Next<int (*)(int, int, int, const void*, socklen_t)>("setsockopt");
  if (IsCan(fd) && level == SOL_CAN_RAW) return 0;
  if (IsCan(fd) && level == SOL_SOCKET && name == SO_TIMESTAMP) return 0;
  return real(fd, level, name, value, length);
}

ssize_t write(int fd, const void* data, size_t length) {
  static auto real = Next<ssize_t (*)(int, const void*, size_t)>("write");
  if (IsCan(fd)) return Broadcast(fd, data, length);
  return real(fd, data, length);
}

ssize_t send(int fd, const void* data, size_t length, int flags) {
  static auto real = Next<ssize_t (*)(int, const void*, size_t, int)>("send");
  if (IsCan(fd)) return Broadcast(fd, data, length);
  return real(fd, data, length, flags);
}

ssize_t sendto(int fd, const void* data, size_t length, int flags, const sockaddr* address,
               socklen_t address_length) {
  static auto real =
      Next<ssize_t (*)(int, const void*, size_t, int, const sockaddr*, socklen_t)>("sendto");
  if (IsCan(fd)) return Broadcast(fd, data, length);
  return real(fd, data, length, flags, address, address_length);
}

ssize_t recvmsg(int fd, msghdr* message, int flags) {
  static auto real = Next<ssize_t (*)(int, msghdr*, int)>("recvmsg");
  if (!IsCan(fd)) return real(fd, message, flags);
  void* name = message->msg_name;
  const socklen_t name_length = message->msg_namelen;
  void* control = message->msg_control;
  const std::size_t control_length = message->msg_controllen;
  message->msg_name = nullptr;
  message->msg_namelen = 0;
  message->msg_control = nullptr;
  message->msg_controllen = 0;
  const ssize_t n = real(fd, message, flags);
  message->msg_name = name;
  message->msg_namelen = 0;
  message->msg_control = control;
  message->msg_controllen = 0;
  // The receive time as SO_TIMESTAMP would give it (candump -L prints it).
  if (n >= 0 && control && control_length >= CMSG_SPACE(sizeof(timeval))) {
    message->msg_controllen = CMSG_SPACE(sizeof(timeval));
    cmsghdr* header = CMSG_FIRSTHDR(message);
    header->cmsg_level = SOL_SOCKET;
    header->cmsg_type = SO_TIMESTAMP;
    header->cmsg_len = CMSG_LEN(sizeof(timeval));
    timeval now{};
    gettimeofday(&now, nullptr);
    std::memcpy(CMSG_DATA(header), &now, sizeof(now));
  }
  if (n >= 0 && name && name_length >= sizeof(sockaddr_can)) {
    sockaddr_can* can = static_cast<sockaddr_can*>(name);
    std::memset(can, 0, sizeof(*can));
    can->can_family = AF_CAN;
    std::lock_guard lock(mutex);
    can->can_ifindex = sockets[fd].ifindex;
    message->msg_namelen = sizeof(sockaddr_can);
  }
  return n;
}

ssize_t recvfrom(int fd, void* data, size_t length, int flags, sockaddr* address,
                 socklen_t* address_length) {
  static auto real = Next<ssize_t (*)(int, void*, size_t, int, sockaddr*, socklen_t*)>("recvfrom");
  if (!IsCan(fd)) return real(fd, data, length, flags, address, address_length);
  const ssize_t n = real(fd, data, length, flags, nullptr, nullptr);
  if (n >= 0 && address && address_length && *address_length >= sizeof(sockaddr_can)) {
    sockaddr_can* can = reinterpret_cast<sockaddr_can*>(address);
    std::memset(can, 0, sizeof(*can));
    can->can_family = AF_CAN;
    std::lock_guard lock(mutex);
    can->can_ifindex = sockets[fd].ifindex;
    *address_length = sizeof(sockaddr_can);
  }
  return n;
}

}  // extern "C"
