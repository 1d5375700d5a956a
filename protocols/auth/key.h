// The key that authenticates what moves the arm: calibration requests (daemon/auth.h) and the
// trajectories the daemon sends to the arm's driver (protocols/trajectory/trajectory_signature.h).
// One key, one HMAC-SHA256 (libsodium's crypto_auth_hmacsha256); each message type signs under
// its own domain string, so a tag of one type is never valid for another.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::auth {

inline constexpr std::size_t kKeyBytes = 32;
inline constexpr std::size_t kTagBytes = 32;
// A key with fewer distinct byte values is refused as weak (all zero, a repeated byte or a short
// repeated pattern); 32 random bytes have about 30.
inline constexpr int kMinDistinctKeyBytes = 8;
using Key = std::array<std::uint8_t, kKeyBytes>;

// Reads a key file: 64 hex characters (one optional trailing newline); refuses a weak key. With
// `require_private`, refuses a file that its group or others may read or write (a service's
// own key).
Expected<Key> ReadKeyFile(const std::string& path, bool require_private);
// Writes a new random key with mode 0600; refuses to overwrite an existing file.
Status GenerateKeyFile(const std::string& path);

// HMAC-SHA256 with `key` over the bytes of `domain` followed by `message` (kTagBytes).
std::vector<std::uint8_t> Tag(const Key& key, std::string_view domain,
                              std::span<const std::uint8_t> message);
// Whether `tag` is that HMAC; compares in constant time. A tag of another length is not.
bool TagMatches(const Key& key, std::string_view domain, std::span<const std::uint8_t> message,
                std::span<const std::uint8_t> tag);

// `bytes` random bytes from the system's generator, as lower-case hex.
std::string RandomHex(std::size_t bytes);

// Canonical encodings, independent of LCM's: integers big-endian, strings and byte arrays as a
// 4-byte big-endian length and their bytes, doubles as their IEEE 754 bits.
void AppendUint(std::vector<std::uint8_t>& out, std::uint64_t value, int bytes);
void AppendString(std::vector<std::uint8_t>& out, std::string_view text);
void AppendDouble(std::vector<std::uint8_t>& out, double value);

}  // namespace selfcal::auth
