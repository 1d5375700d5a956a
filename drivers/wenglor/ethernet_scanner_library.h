// Loads the vendor's libEthernetScanner.so at run time (dlopen) and resolves every function the
// driver calls. The same code loads our simulator (tools/sim_wenglor), so tests run the real
// loading path. A missing file or symbol is an error that names the path and the symbol.
#pragma once

#include <memory>
#include <string>

#include "core/util/expected.h"
#include "drivers/wenglor/ethernet_scanner_api.h"

namespace selfcal::wenglor {

class EthernetScannerLibrary {
 public:
  // Opens `path` with RTLD_NOW | RTLD_LOCAL; RTLD_LOCAL keeps two loaded copies apart.
  static Expected<std::unique_ptr<EthernetScannerLibrary>> Load(const std::string& path);
  ~EthernetScannerLibrary();
  EthernetScannerLibrary(const EthernetScannerLibrary&) = delete;
  EthernetScannerLibrary& operator=(const EthernetScannerLibrary&) = delete;

  const std::string& path() const { return path_; }
  // The library's version text (EthernetScanner_GetVersion), empty when it reports none.
  std::string Version() const;

  api::ConnectFn connect = nullptr;
  api::DisconnectFn disconnect = nullptr;
  api::GetConnectStatusFn get_connect_status = nullptr;
  api::GetXZIExtendedFn get_xzi_extended = nullptr;
  api::GetInfoFn get_info = nullptr;
  api::GetDllFiFoStateFn get_dll_fifo_state = nullptr;
  api::ResetDllFiFoFn reset_dll_fifo = nullptr;
  api::WriteDataFn write_data = nullptr;
  api::ReadDataFn read_data = nullptr;
  api::GetVersionFn get_version = nullptr;

 private:
  EthernetScannerLibrary(std::string path, void* handle)
      : path_(std::move(path)), handle_(handle) {}
  std::string path_;
  void* handle_ = nullptr;
};

}  // namespace selfcal::wenglor
