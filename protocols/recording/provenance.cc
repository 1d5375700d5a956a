#include "protocols/recording/provenance.h"

#include <sodium.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>

namespace selfcal::recording {

Expected<std::string> FileSha256(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  crypto_hash_sha256_state state;
  crypto_hash_sha256_init(&state);
  std::array<char, 1 << 16> buffer;
  while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0) {
    crypto_hash_sha256_update(&state, reinterpret_cast<const unsigned char*>(buffer.data()),
                              static_cast<unsigned long long>(in.gcount()));
  }
  if (in.bad()) return Error{path + ": read failed: " + std::strerror(errno)};
  std::array<unsigned char, crypto_hash_sha256_BYTES> digest;
  crypto_hash_sha256_final(&state, digest.data());
  std::array<char, 2 * crypto_hash_sha256_BYTES + 1> hex;
  sodium_bin2hex(hex.data(), hex.size(), digest.data(), digest.size());
  return std::string(hex.data());
}

namespace {

std::string ShellQuoted(const std::string& argument) {
  if (!argument.empty() && argument.find_first_of(" \t\n'\"\\$`*?;&|<>()") == std::string::npos) {
    return argument;
  }
  std::string quoted = "'";
  for (const char c : argument) {
    if (c == '\'') {
      quoted.append("'\\''");
    } else {
      quoted.push_back(c);
    }
  }
  return quoted + "'";
}

}  // namespace

std::string ProcessCommandLine() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string line;
  std::string argument;
  while (std::getline(in, argument, '\0')) {
    if (!line.empty()) line.push_back(' ');
    line += ShellQuoted(argument);
  }
  return line;
}

Expected<Provenance> MakeProvenance(
    const std::string& software, const std::vector<std::pair<std::string, std::string>>& inputs) {
  Provenance provenance{software, ProcessCommandLine(), {}};
  for (const auto& [role, path] : inputs) {
    auto digest = FileSha256(path);
    if (!digest) return digest.error();
    provenance.inputs.push_back({role, path, *digest});
  }
  return provenance;
}

}  // namespace selfcal::recording
