// The history of sessions, results and requests, in SQLite (storage/history.sqlite).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"

struct sqlite3;

namespace selfcal::daemon {

// One row of the request history.
struct RequestRow {
  std::int64_t received_utime = 0;
  std::int64_t request_utime = 0;
  std::string nonce;
  int action = 0;
  std::string requested_by;
  std::string verdict;
  bool nonce_used = false;
};

struct SessionRecord {
  std::string id;
  std::int64_t started_utime = 0;
  std::int64_t ended_utime = 0;
  std::string plan;
  std::string requested_by;
  std::string nonce;
  std::string state;  // recording, calibrating, accepted, rejected, aborted, failed, incomplete
  std::string reason;
  double rms_before = -1;  // m, -1 = not known
  double rms_after = -1;
  int iterations = 0;
  double runtime = 0;    // s
  std::string model_id;  // the installed model (accepted sessions)
  std::string change;    // what changed against the model it started from, in words
};

class History {
 public:
  // Creates the schema when the file is new. `read_only` for `selfcal history`. The request
  // history keeps the newest `requests_kept` rows.
  static Expected<std::unique_ptr<History>> Open(const std::string& path, bool read_only,
                                                 std::int64_t requests_kept = 10'000);
  ~History();

  Status UpsertSession(const SessionRecord& record);
  // Adds a request and removes the oldest beyond `requests_kept`, remembering the newest
  // request_utime of a used nonce it removed (ForgottenNoncesUpTo), in one transaction.
  Status LogRequest(std::int64_t received_utime, std::int64_t request_utime,
                    const std::string& nonce, int action, const std::string& requested_by,
                    const std::string& verdict, bool nonce_used);
  // As LogRequest for every row, all in one transaction: one commit (one fsync) for a whole
  // batch of requests, all of them on disk or none.
  Status LogRequests(const std::vector<RequestRow>& rows);
  // Replaces the verdict logged for the request with `nonce` (an accepted request whose action
  // then failed, such as a rollback with no previous model).
  Status SetRequestVerdict(const std::string& nonce, const std::string& verdict);
  // The newest request_utime of a used nonce trimmed from the history; the lowest int64 if none.
  Expected<std::int64_t> ForgottenNoncesUpTo();
  // The history's files (database, WAL, shared memory) on disk, for the storage quota.
  std::uint64_t FileBytes() const;
  Status LogModelEvent(std::int64_t utime, const std::string& event, const std::string& model_id);
  // Newest first.
  Expected<std::vector<SessionRecord>> Sessions(int limit);
  // Nonces of authentic, fresh requests (used up) signed after `since_utime`.
  Expected<std::vector<std::pair<std::string, std::int64_t>>> NoncesSince(std::int64_t since_utime);
  // Rows in the request history.
  Expected<std::int64_t> RequestRows();
  const std::string& path() const { return path_; }

 private:
  History(std::string path, sqlite3* db, std::int64_t requests_kept)
      : path_(std::move(path)), db_(db), requests_kept_(requests_kept) {}
  Status Exec(const std::string& sql);
  // Whether the sessions table has a column (histories of older versions lack newer ones).
  bool HasSessionColumn(const char* column);
  Status InsertRequests(const std::vector<RequestRow>& rows);
  Status TrimRequests();
  std::string path_;
  sqlite3* db_;
  std::int64_t requests_kept_;
};

}  // namespace selfcal::daemon
