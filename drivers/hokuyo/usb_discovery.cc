#include "drivers/hokuyo/usb_discovery.h"

#include <libusb-1.0/libusb.h>

#include <atomic>
#include <filesystem>
#include <thread>

namespace selfcal::hokuyo {
namespace {

std::string PortPath(libusb_device* device) {
  std::uint8_t ports[8];
  const int count = libusb_get_port_numbers(device, ports, sizeof(ports));
  std::string path = std::to_string(libusb_get_bus_number(device));
  for (int i = 0; i < count; ++i) {
    path.push_back(i == 0 ? '-' : '.');
    path.append(std::to_string(ports[i]));
  }
  return path;
}

UsbDevice Describe(libusb_device* device, const libusb_device_descriptor& descriptor) {
  UsbDevice out;
  out.bus = libusb_get_bus_number(device);
  out.address = libusb_get_device_address(device);
  out.port_path = PortPath(device);
  out.product_id = descriptor.idProduct;
  out.tty = TtyForPortPath(out.port_path);
  return out;
}

class LibusbWatcher final : public UsbHotplugWatcher {
 public:
  explicit LibusbWatcher(Callback callback) : callback_(std::move(callback)) {}
  ~LibusbWatcher() override {
    stop_.store(true);
    if (context_ && armed_) libusb_hotplug_deregister_callback(context_, handle_);
    if (thread_.joinable()) thread_.join();
    if (context_) libusb_exit(context_);
  }

  Status Arm() {
    if (const int rc = libusb_init(&context_); rc != 0) {
      context_ = nullptr;
      return Error{std::string("libusb_init: ") + libusb_error_name(rc)};
    }
    if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
      return Error{"libusb has no hotplug support on this platform"};
    }
    const int rc = libusb_hotplug_register_callback(
        context_,
        static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                          LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
        LIBUSB_HOTPLUG_ENUMERATE, kHokuyoVendorId, LIBUSB_HOTPLUG_MATCH_ANY,
        LIBUSB_HOTPLUG_MATCH_ANY, &LibusbWatcher::OnHotplug, this, &handle_);
    if (rc != LIBUSB_SUCCESS) {
      return Error{std::string("libusb_hotplug_register_callback: ") + libusb_error_name(rc)};
    }
    armed_ = true;
    thread_ = std::thread([this] {
      while (!stop_.load()) {
        timeval timeout{0, 100000};
        libusb_handle_events_timeout_completed(context_, &timeout, nullptr);
      }
    });
    return OkStatus();
  }

  bool armed() const override { return armed_; }

 private:
  static int OnHotplug(libusb_context*, libusb_device* device, libusb_hotplug_event event,
                       void* user) {
    auto* self = static_cast<LibusbWatcher*>(user);
    libusb_device_descriptor descriptor{};
    libusb_get_device_descriptor(device, &descriptor);
    self->callback_(event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED ? Event::kArrived : Event::kLeft,
                    Describe(device, descriptor));
    return 0;  // stay registered
  }

  Callback callback_;
  libusb_context* context_ = nullptr;
  libusb_hotplug_callback_handle handle_{};
  bool armed_ = false;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

std::string TtyForPortPath(const std::string& port_path, const std::string& sysfs_root) {
  namespace fs = std::filesystem;
  std::error_code error;
  // Interfaces are "<port path>:<configuration>.<interface>"; CDC-ACM puts a tty/ttyACMn below.
  for (const auto& entry : fs::directory_iterator(sysfs_root, error)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(port_path + ":")) continue;
    for (const auto& tty : fs::directory_iterator(entry.path() / "tty", error)) {
      return "/dev/" + tty.path().filename().string();
    }
  }
  return "";
}

Expected<std::vector<UsbDevice>> ListHokuyoUsb() {
  libusb_context* context = nullptr;
  if (const int rc = libusb_init(&context); rc != 0) {
    return Error{std::string("libusb_init: ") + libusb_error_name(rc)};
  }
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context, &list);
  std::vector<UsbDevice> found;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0) continue;
    if (descriptor.idVendor != kHokuyoVendorId) continue;
    found.push_back(Describe(list[i], descriptor));
  }
  if (list) libusb_free_device_list(list, 1);
  libusb_exit(context);
  if (count < 0) {
    return Error{std::string("libusb_get_device_list: ") +
                 libusb_error_name(static_cast<int>(count))};
  }
  return found;
}

Expected<std::unique_ptr<UsbHotplugWatcher>> UsbHotplugWatcher::Start(Callback callback) {
  auto watcher = std::make_unique<LibusbWatcher>(std::move(callback));
  if (auto status = watcher->Arm(); !status) return status.error();
  return std::unique_ptr<UsbHotplugWatcher>(std::move(watcher));
}

}  // namespace selfcal::hokuyo
