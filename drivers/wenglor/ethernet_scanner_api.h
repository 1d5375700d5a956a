// The C interface of Wenglor's closed EthernetScanner library (weCat3D SDK), as documented in the
// "weCat3D MLSL / MLWL DLL Interface Description" and summarised in shared/protocols.md section 2.
// Written from those facts: function signatures (for dlsym) and the documented return codes. The
// vendor header is not included: the library is loaded at run time, so our build never needs it.
// On Linux the vendor's `_stdcall` is empty, so these are plain C functions.
#pragma once

#include <cstdint>

namespace selfcal::wenglor::api {

// Connection states reported by EthernetScanner_GetConnectStatus.
inline constexpr int kDisconnected = 0;
inline constexpr int kConnecting = 1;
inline constexpr int kDisconnecting = 2;
inline constexpr int kConnected = 3;

// EthernetScanner_GetXZIExtended: number of values written, or one of these.
inline constexpr int kGetXziNoNewScan = -1;
inline constexpr int kGetXziInvalidLinData = -2;
inline constexpr int kGetXziInvalidBuffer = -3;

// EthernetScanner_GetInfo.
inline constexpr int kGetInfoError = -1;
inline constexpr int kGetInfoSmallBuffer = -2;
inline constexpr int kGetInfoNoValidInfo = -3;
inline constexpr int kGetInfoInvalidXml = -4;

// EthernetScanner_ReadData.
inline constexpr int kReadDataOk = 1;
inline constexpr int kReadDataSmallBuffer = -1;
inline constexpr int kReadDataNotSupportedMode = -2;
inline constexpr int kReadDataFeatureNotDefined = -3;

// Generic results (WriteData, ResetDllFiFo).
inline constexpr int kOk = 0;
inline constexpr int kError = -1;

// Sizes.
inline constexpr int kScanXMax = 2048;               // columns per profile (MLWL; MLSL has 1280)
inline constexpr int kPeaksPerColumnMax = 4;         // signals per column
inline constexpr int kBufferSizeMax = 2050 * 2050;   // raw buffer bytes
inline constexpr int kGetInfoSizeMax = 128 * 1024;   // info XML bytes
inline constexpr int kPictureCounterModulo = 65536;  // the picture counter is 16 bit

// Function pointer types, one per exported symbol.
extern "C" {
using ConnectFn = void* (*)(char* ip, char* port, int timeout_ms);
using ConnectExFn = void (*)(void* handle, char* ip, char* port, int timeout_ms);
using DisconnectFn = void* (*)(void* handle);
using GetConnectStatusFn = void (*)(void* handle, int* status);
using GetXZIExtendedFn = int (*)(void* handle, double* x_mm, double* z_mm, int* intensity,
                                 int* peak_width, int buffer_values, unsigned int* encoder,
                                 unsigned char* user_io, int timeout_ms, unsigned char* raw,
                                 int raw_bytes, int* picture_counter);
using GetInfoFn = int (*)(void* handle, char* info, int info_bytes, char* mode);
using GetDllFiFoStateFn = int (*)(void* handle);
using ResetDllFiFoFn = int (*)(void* handle);
using WriteDataFn = int (*)(void* handle, char* command, int command_bytes);
using ReadDataFn = int (*)(void* handle, char* property, char* value, int value_bytes,
                           int cache_time_ms);
using GetVersionFn = int (*)(unsigned char* version, int version_bytes);
}

}  // namespace selfcal::wenglor::api
