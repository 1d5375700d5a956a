// Hokuyo sensors on USB, found by vendor id through libusb and mapped to their CDC-ACM tty
// (/sys/bus/usb/devices/<port path>:<config>.<interface>/tty/ttyACMn). Hotplug: a callback when
// one arrives or leaves. Without a USB bus (containers, CI) the list is empty, not an error.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::hokuyo {

inline constexpr std::uint16_t kHokuyoVendorId = 0x15d1;

struct UsbDevice {
  int bus = 0;
  int address = 0;
  std::string port_path;  // "1-2.4": bus and port numbers, as sysfs names it
  std::uint16_t product_id = 0;
  std::string tty;  // "/dev/ttyACM0", empty when no tty is bound (yet)
};

// The Hokuyos attached now.
Expected<std::vector<UsbDevice>> ListHokuyoUsb();

// The tty bound to a USB device under `sysfs_root` (default /sys/bus/usb/devices).
std::string TtyForPortPath(const std::string& port_path,
                           const std::string& sysfs_root = "/sys/bus/usb/devices");

// Watches for Hokuyos arriving and leaving (libusb hotplug) on a thread of its own.
class UsbHotplugWatcher {
 public:
  enum class Event { kArrived, kLeft };
  using Callback = std::function<void(Event, const UsbDevice&)>;
  // Error when libusb cannot start or the platform lacks hotplug support.
  static Expected<std::unique_ptr<UsbHotplugWatcher>> Start(Callback callback);
  virtual ~UsbHotplugWatcher() = default;
  virtual bool armed() const = 0;
};

}  // namespace selfcal::hokuyo
