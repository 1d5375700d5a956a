// The daemon's request path on any bytes: DecodeLcm<calibration_request_t> and the HMAC, time
// and nonce checks of RequestAuthenticator, as Daemon::OnRequest runs them. Half of the inputs
// are requests the fuzzer fills and signs with the daemon's key and then corrupts at chosen
// bytes, so the checks behind the signature are reached too. Properties: never a crash; a request
// is accepted only if it is exactly what was signed; the same request is never accepted twice.
#include <cstdint>
#include <cstring>
#include <vector>

#include "daemon/auth.h"
#include "protocols/lcm_log/lcm_codec.h"

namespace {

using selfcal::calibration_request_t;
using namespace selfcal::daemon;

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t Byte() { return at_ < size_ ? data_[at_++] : 0; }
  std::int64_t Int64() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v = v << 8 | Byte();
    return static_cast<std::int64_t>(v);
  }
  std::string Text() {
    std::string s(Byte() % 40, ' ');
    for (char& c : s) c = static_cast<char>(Byte());
    return s;
  }
  std::size_t left() const { return at_ < size_ ? size_ - at_ : 0; }
  const std::uint8_t* rest() const { return data_ + at_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

selfcal::auth::Key FuzzKey() {
  selfcal::auth::Key key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(i * 37 + 11);
  return key;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const selfcal::auth::Key key = FuzzKey();
  Input in(data, size);
  const std::uint8_t mode = in.Byte();
  const std::int64_t now = in.Int64();
  RequestAuthenticator authenticator(key, "fuzz-robot", 1 + (mode >> 4));  // a window of 1..16 s
  std::vector<std::uint8_t> bytes;
  std::vector<std::uint8_t> signed_canonical;
  if (mode & 1) {
    calibration_request_t request;
    // Wrapping arithmetic: the input picks any time, the fuzzer itself must not overflow.
    request.utime = (mode & 2) ? static_cast<std::int64_t>(static_cast<std::uint64_t>(now) -
                                                           std::uint64_t{in.Byte()} * 100'000)
                               : in.Int64();
    request.action = static_cast<std::int8_t>(in.Byte() % 5);
    request.robot_id = (mode & 8) ? in.Text() : "fuzz-robot";  // ours, or any other
    request.nonce = in.Text();
    request.plan_name = in.Text();
    request.requested_by = in.Text();
    request.tag_length = 0;
    if (mode & 4) SignRequest(request, key);
    signed_canonical = CanonicalRequestBytes(request);
    bytes = selfcal::EncodeLcm(request);
    // Corrupt chosen bytes (position, xor) pairs.
    const int flips = in.Byte() % 4;
    for (int i = 0; i < flips && !bytes.empty(); ++i) {
      const std::size_t at = (std::size_t{in.Byte()} << 8 | in.Byte()) % bytes.size();
      bytes[at] ^= in.Byte();
    }
  } else {
    bytes.assign(in.rest(), in.rest() + in.left());
    if (mode & 2) {
      // The right fingerprint, so the fuzzer works on the body.
      const auto hash = static_cast<std::uint64_t>(calibration_request_t::getHash());
      std::vector<std::uint8_t> fingerprint(8);
      for (std::size_t i = 0; i < 8; ++i)
        fingerprint[i] = static_cast<std::uint8_t>(hash >> (56 - 8 * i));
      bytes.insert(bytes.begin(), fingerprint.begin(), fingerprint.end());
    }
  }
  const auto decoded = selfcal::DecodeLcm<calibration_request_t>(bytes, "CALIBRATION_REQUEST");
  if (!decoded.ok()) return 0;
  const Verdict first = authenticator.Check(*decoded, now);
  (void)VerdictText(first);
  if (first == Verdict::kAccepted) {
    // Only the signed request itself passes: no field can change under a valid tag.
    if (!(mode & 1) || !(mode & 4) || CanonicalRequestBytes(*decoded) != signed_canonical) {
      __builtin_trap();
    }
  }
  if (authenticator.Check(*decoded, now) == Verdict::kAccepted) __builtin_trap();  // a replay
  return 0;
}
