#include "daemon/sessions.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <system_error>

#include "core/util/atomic_file.h"

namespace selfcal::daemon {
namespace fs = std::filesystem;

std::string NewSessionId(std::int64_t now_utime) {
  static std::atomic<int> counter{0};
  const std::time_t seconds = static_cast<std::time_t>(now_utime / 1000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[64];
  std::snprintf(text, sizeof(text), "%04d%02d%02dT%02d%02d%02d.%03dZ-%d", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                static_cast<int>((now_utime / 1000) % 1000), counter++ % 1000);
  return text;
}

SessionStore::SessionStore(std::string storage_folder)
    : folder_(std::move(storage_folder) + "/sessions") {}

Status SessionStore::Create(const SessionMeta& meta) {
  std::error_code error;
  fs::create_directories(SessionFolder(meta.id), error);
  if (error)
    return Error{SessionFolder(meta.id) + ": cannot create the session folder: " + error.message()};
  return Write(meta);
}

Status SessionStore::Write(const SessionMeta& meta) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "id" << YAML::Value << meta.id;
  out << YAML::Key << "plan" << YAML::Value << meta.plan;
  out << YAML::Key << "requested_by" << YAML::Value << meta.requested_by;
  out << YAML::Key << "nonce" << YAML::Value << meta.nonce;
  out << YAML::Key << "started_utime" << YAML::Value << meta.started_utime;
  out << YAML::Key << "ended_utime" << YAML::Value << meta.ended_utime;
  out << YAML::Key << "status" << YAML::Value << meta.status;
  out << YAML::Key << "reason" << YAML::Value << meta.reason;
  out << YAML::EndMap;
  return WriteFileAtomically(SessionFolder(meta.id) + "/" + kSessionFile,
                             std::string(out.c_str()) + "\n");
}

Expected<SessionMeta> SessionStore::Read(const std::string& id) const {
  const std::string path = SessionFolder(id) + "/" + kSessionFile;
  try {
    const YAML::Node node = YAML::LoadFile(path);
    SessionMeta meta;
    meta.id = node["id"].as<std::string>();
    meta.plan = node["plan"].as<std::string>("");
    meta.requested_by = node["requested_by"].as<std::string>("");
    meta.nonce = node["nonce"].as<std::string>("");
    meta.started_utime = node["started_utime"].as<std::int64_t>(0);
    meta.ended_utime = node["ended_utime"].as<std::int64_t>(0);
    meta.status = node["status"].as<std::string>();
    meta.reason = node["reason"].as<std::string>("");
    return meta;
  } catch (const YAML::Exception& e) {
    return Error{path + ": " + e.what()};
  }
}

Expected<std::vector<SessionMeta>> SessionStore::List() const {
  std::vector<SessionMeta> sessions;
  std::error_code error;
  if (!fs::exists(folder_, error)) return sessions;
  for (const auto& entry : fs::directory_iterator(folder_, error)) {
    if (!entry.is_directory()) continue;
    const std::string id = entry.path().filename().string();
    auto meta = Read(id);
    if (!meta) {
      // A folder without readable metadata is a session that died before its first write.
      SessionMeta broken;
      broken.id = id;
      broken.status = "incomplete";
      broken.reason = "no readable session.yaml";
      meta = broken;
    }
    std::uint64_t bytes = 0;
    for (const auto& file : fs::recursive_directory_iterator(entry.path(), error)) {
      if (file.is_regular_file(error)) bytes += file.file_size(error);
    }
    meta->bytes = bytes;
    sessions.push_back(std::move(meta).value());
  }
  if (error) return Error{folder_ + ": cannot list the sessions: " + error.message()};
  std::sort(sessions.begin(), sessions.end(),
            [](const SessionMeta& a, const SessionMeta& b) { return a.id < b.id; });
  return sessions;
}

Expected<std::vector<std::string>> SessionStore::MarkInterrupted(std::int64_t now_utime) {
  auto sessions = List();
  if (!sessions) return sessions.error();
  std::vector<std::string> marked;
  for (auto& meta : *sessions) {
    if (meta.status != "recording" && meta.status != "recorded" && meta.status != "calibrating")
      continue;
    meta.reason = "interrupted while " + meta.status + " (the daemon stopped); not usable";
    meta.status = "incomplete";
    meta.ended_utime = now_utime;
    if (!fs::exists(SessionFolder(meta.id) + "/" + kSessionFile)) {
      std::error_code ignored;
      fs::create_directories(SessionFolder(meta.id), ignored);
    }
    auto status = Write(meta);
    if (!status) return status.error();
    marked.push_back(meta.id);
  }
  return marked;
}

Expected<std::vector<std::string>> SessionStore::EnforceQuota(std::uint64_t quota_bytes,
                                                              const std::set<std::string>& keep,
                                                              std::uint64_t other_bytes) {
  auto sessions = List();
  if (!sessions) return sessions.error();
  std::uint64_t total = other_bytes;
  for (const auto& meta : *sessions) total += meta.bytes;
  std::vector<std::string> removed;
  for (const auto& meta : *sessions) {  // oldest first
    if (total <= quota_bytes) break;
    if (keep.count(meta.id)) continue;
    std::error_code error;
    fs::remove_all(SessionFolder(meta.id), error);
    if (error) return Error{SessionFolder(meta.id) + ": cannot remove: " + error.message()};
    total -= meta.bytes;
    removed.push_back(meta.id);
  }
  return removed;
}

}  // namespace selfcal::daemon
