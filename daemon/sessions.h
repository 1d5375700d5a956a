// Session folders: storage/sessions/<id>/{recording.lcmlog, session.yaml}.
// session.yaml is written atomically at every step; the log is written as .partial and renamed on
// completion, so a crash never leaves a session that looks complete.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::daemon {

struct SessionMeta {
  std::string id;
  std::string plan;
  std::string requested_by;
  std::string nonce;
  std::int64_t started_utime = 0;
  std::int64_t ended_utime = 0;
  // recording -> recorded -> calibrating -> accepted | rejected; or aborted, failed, incomplete.
  std::string status = "recording";
  std::string reason;
  std::uint64_t bytes = 0;  // filled by List()
};

inline constexpr const char* kRecordingFile = "recording.lcmlog";
inline constexpr const char* kSessionFile = "session.yaml";

// A session id from the current time: sortable, unique within a process.
std::string NewSessionId(std::int64_t now_utime);

class SessionStore {
 public:
  explicit SessionStore(std::string storage_folder);
  const std::string& folder() const { return folder_; }
  std::string SessionFolder(const std::string& id) const { return folder_ + "/" + id; }
  std::string RecordingPath(const std::string& id) const {
    return SessionFolder(id) + "/" + kRecordingFile;
  }

  // Creates the folder and writes session.yaml (fsync'd, atomic).
  Status Create(const SessionMeta& meta);
  Status Write(const SessionMeta& meta);
  Expected<SessionMeta> Read(const std::string& id) const;
  // All sessions, oldest first, with their size on disk.
  Expected<std::vector<SessionMeta>> List() const;
  // Sessions that a crash interrupted (recording, recorded, calibrating) become `incomplete`.
  Expected<std::vector<std::string>> MarkInterrupted(std::int64_t now_utime);
  // Removes the oldest sessions, except `keep`, until their total and `other_bytes` (the
  // history) are within `quota_bytes`.
  Expected<std::vector<std::string>> EnforceQuota(std::uint64_t quota_bytes,
                                                  const std::set<std::string>& keep,
                                                  std::uint64_t other_bytes = 0);

 private:
  std::string folder_;
};

}  // namespace selfcal::daemon
