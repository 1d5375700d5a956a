#include "drivers/wenglor/ethernet_scanner_library.h"

#include <dlfcn.h>

#include <array>

namespace selfcal::wenglor {
namespace {

// Resolves `name` into `function`; the error names the library path and the symbol.
template <typename Function>
Status Resolve(void* handle, const std::string& path, const char* name, Function& function) {
  dlerror();  // clear any earlier error so that a NULL symbol is told apart from a failure
  void* symbol = dlsym(handle, name);
  const char* reason = dlerror();
  if (symbol == nullptr || reason != nullptr) {
    return Error{path + ": missing symbol " + name +
                 (reason != nullptr ? std::string(" (") + reason + ")" : std::string())};
  }
  function = reinterpret_cast<Function>(symbol);
  return OkStatus();
}

}  // namespace

Expected<std::unique_ptr<EthernetScannerLibrary>> EthernetScannerLibrary::Load(
    const std::string& path) {
  if (path.empty()) return Error{"no EthernetScanner library path configured (library_path)"};
  dlerror();
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* reason = dlerror();
    return Error{"cannot load EthernetScanner library '" + path +
                 "': " + (reason != nullptr ? reason : "unknown dlopen error")};
  }
  std::unique_ptr<EthernetScannerLibrary> library(new EthernetScannerLibrary(path, handle));
  auto& l = *library;
  for (const Status& status : std::array<Status, 10>{
           Resolve(handle, path, "EthernetScanner_Connect", l.connect),
           Resolve(handle, path, "EthernetScanner_Disconnect", l.disconnect),
           Resolve(handle, path, "EthernetScanner_GetConnectStatus", l.get_connect_status),
           Resolve(handle, path, "EthernetScanner_GetXZIExtended", l.get_xzi_extended),
           Resolve(handle, path, "EthernetScanner_GetInfo", l.get_info),
           Resolve(handle, path, "EthernetScanner_GetDllFiFoState", l.get_dll_fifo_state),
           Resolve(handle, path, "EthernetScanner_ResetDllFiFo", l.reset_dll_fifo),
           Resolve(handle, path, "EthernetScanner_WriteData", l.write_data),
           Resolve(handle, path, "EthernetScanner_ReadData", l.read_data),
           Resolve(handle, path, "EthernetScanner_GetVersion", l.get_version)}) {
    if (!status.ok()) return status.error();
  }
  return library;
}

EthernetScannerLibrary::~EthernetScannerLibrary() {
  if (handle_ != nullptr) dlclose(handle_);
}

std::string EthernetScannerLibrary::Version() const {
  std::array<unsigned char, 256> buffer{};
  const int rc = get_version(buffer.data(), static_cast<int>(buffer.size()));
  if (rc < 0) return {};
  buffer.back() = 0;
  return std::string(reinterpret_cast<const char*>(buffer.data()));
}

}  // namespace selfcal::wenglor
