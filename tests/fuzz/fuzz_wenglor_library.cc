// A stand-in for Wenglor's libEthernetScanner.so that answers from the fuzz input
// (FuzzWenglorSetInput): the info XML's column count, and for every EthernetScanner_GetXZIExtended
// a return code, a picture counter and column values of any kind (0/0 for no return, NaN,
// infinities, huge values). Settings written with WriteData read back as written, so Connect()
// succeeds and the decoding is what gets fuzzed. Built without sanitizers: a data source only.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <string>

namespace {

const std::uint8_t* input = nullptr;
std::size_t input_size = 0;
std::size_t input_at = 0;
std::map<std::string, std::string> settings;
int handle_storage = 0;

std::uint8_t Byte() { return input_at < input_size ? input[input_at++] : 0; }
bool Exhausted() { return input_at >= input_size; }

double Coordinate() {
  const std::uint8_t b = Byte();
  switch (b) {
    case 0:
      return 0.0;  // with z = 0: no return
    case 1:
      return std::numeric_limits<double>::quiet_NaN();
    case 2:
      return std::numeric_limits<double>::infinity();
    case 3:
      return -std::numeric_limits<double>::infinity();
    case 4:
      return 1e300;
    default:
      return (b - 128) * 3.7;
  }
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) void FuzzWenglorSetInput(const std::uint8_t* data,
                                                                std::size_t size) {
  input = data;
  input_size = size;
  input_at = 0;
  settings.clear();
}

__attribute__((visibility("default"))) void* EthernetScanner_Connect(char*, char*, int) {
  return &handle_storage;
}
__attribute__((visibility("default"))) void* EthernetScanner_Disconnect(void*) { return nullptr; }
__attribute__((visibility("default"))) void EthernetScanner_GetConnectStatus(void*, int* status) {
  *status = 3;  // connected
}
__attribute__((visibility("default"))) int EthernetScanner_GetInfo(void*, char* info,
                                                                   int info_bytes, char*) {
  const int columns = 1 + (Byte() << 4 | Byte()) % 2100;  // beyond the library's 2048 too
  const std::string xml =
      "<?xml version=\"1.0\"?>\n<info><general><ordernumber>MLSL236</ordernumber>"
      "<serialnumber>FUZZ</serialnumber><firmware>f</firmware></general><range>"
      "<workingrange_z_start>180</workingrange_z_start><measuringrange_z>210</measuringrange_z>"
      "<fieldwidth_x_start>100</fieldwidth_x_start><fieldwidth_x_end>200</fieldwidth_x_end>"
      "<pixel_x_max>" +
      std::to_string(columns) + "</pixel_x_max></range></info>\n";
  if (info_bytes <= static_cast<int>(xml.size())) return -2;
  std::memcpy(info, xml.c_str(), xml.size() + 1);
  return 0;
}
__attribute__((visibility("default"))) int EthernetScanner_GetXZIExtended(
    void*, double* x_mm, double* z_mm, int* intensity, int* peak_width, int buffer_values,
    unsigned int* encoder, unsigned char* user_io, int, unsigned char*, int, int* picture_counter) {
  if (Exhausted()) return -1;
  const std::uint8_t kind = Byte();
  *picture_counter = Byte() << 8 | Byte();
  *encoder = Byte();
  *user_io = Byte();
  switch (kind % 8) {
    case 0:
      return -1;  // no new scan
    case 1:
      return -2;
    case 2:
      return -3;
    case 3:
      return -7;  // undocumented
    case 4:
      return Byte() << 8 | Byte();  // any count, also more than the buffer
    default:
      break;
  }
  const int values = std::min(buffer_values, Byte() << 4 | Byte());
  for (int i = 0; i < values; ++i) {
    x_mm[i] = Coordinate();
    z_mm[i] = Coordinate();
    intensity[i] = Byte() << 2;
    peak_width[i] = Byte() % 40;
  }
  return values;
}
__attribute__((visibility("default"))) int EthernetScanner_GetDllFiFoState(void*) {
  return Byte() % 120;
}
__attribute__((visibility("default"))) int EthernetScanner_ResetDllFiFo(void*) { return 0; }
__attribute__((visibility("default"))) int EthernetScanner_WriteData(void*, char* command,
                                                                     int bytes) {
  const std::string text(command, static_cast<std::size_t>(bytes));
  const auto equals = text.find('=');
  if (text.rfind("Set", 0) == 0 && equals != std::string::npos) {
    settings[text.substr(3, equals - 3)] = text.substr(equals + 1);
  }
  return 0;
}
__attribute__((visibility("default"))) int EthernetScanner_ReadData(void*, char* property,
                                                                    char* value, int value_bytes,
                                                                    int) {
  const auto it = settings.find(property);
  if (it == settings.end()) return -3;
  if (value_bytes <= static_cast<int>(it->second.size())) return -1;
  std::memcpy(value, it->second.c_str(), it->second.size() + 1);
  return 1;
}
__attribute__((visibility("default"))) int EthernetScanner_GetVersion(unsigned char* version,
                                                                      int bytes) {
  if (bytes < 5) return -1;
  std::memcpy(version, "fuzz", 5);
  return 0;
}

}  // extern "C"
