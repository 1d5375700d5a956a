#include "core/util/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace selfcal {
namespace {

std::string Reason() { return std::strerror(errno); }

Status FsyncPath(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return Error{path + ": cannot open for fsync: " + Reason()};
  const int rc = ::fsync(fd);
  const std::string reason = Reason();
  ::close(fd);
  if (rc != 0) return Error{path + ": fsync failed: " + reason};
  return OkStatus();
}

std::string ParentFolder(const std::string& path) {
  const auto parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

}  // namespace

Status CommitFile(const std::string& temporary_path, const std::string& final_path) {
  if (auto status = FsyncPath(temporary_path, O_RDONLY); !status) return status;
  if (::rename(temporary_path.c_str(), final_path.c_str()) != 0) {
    return Error{final_path + ": cannot rename " + temporary_path + " into place: " + Reason()};
  }
  return FsyncPath(ParentFolder(final_path), O_RDONLY | O_DIRECTORY);
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  const std::string temporary = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{temporary + ": cannot create: " + Reason()};
  std::size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string reason = Reason();
      ::close(fd);
      ::unlink(temporary.c_str());
      return Error{temporary + ": write failed after " + std::to_string(written) +
                   " bytes: " + reason};
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string reason = Reason();
    ::unlink(temporary.c_str());
    return Error{temporary + ": fsync/close failed: " + reason};
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string reason = Reason();
    ::unlink(temporary.c_str());
    return Error{path + ": cannot rename temporary into place: " + reason};
  }
  return FsyncPath(ParentFolder(path), O_RDONLY | O_DIRECTORY);
}

Expected<std::string> ReadFile(const std::string& path, std::size_t max_bytes) {
  // A folder opens as a stream on Linux and fails only when read, with an exception from inside
  // the stream buffer: say what it is before that.
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return Error{path + ": is a folder, not a file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + Reason()};
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return Error{path + ": cannot read: " + Reason()};
  std::string contents = buffer.str();
  if (contents.size() > max_bytes) {
    return Error{path + ": file is " + std::to_string(contents.size()) + " bytes, more than the " +
                 std::to_string(max_bytes) + " allowed"};
  }
  return contents;
}

}  // namespace selfcal
