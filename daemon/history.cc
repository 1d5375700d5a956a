#include "daemon/history.h"

#include <sqlite3.h>

#include <filesystem>
#include <limits>

namespace selfcal::daemon {
namespace {

// Prepared statement with automatic finalization.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) {
    rc_ = sqlite3_prepare_v2(db, sql, -1, &statement_, nullptr);
  }
  ~Statement() { sqlite3_finalize(statement_); }
  bool ok() const { return rc_ == SQLITE_OK; }
  sqlite3_stmt* get() { return statement_; }
  void Bind(int index, const std::string& text) {
    sqlite3_bind_text(statement_, index, text.c_str(), static_cast<int>(text.size()),
                      SQLITE_TRANSIENT);
  }
  void Bind(int index, std::int64_t value) { sqlite3_bind_int64(statement_, index, value); }
  void Bind(int index, double value) { sqlite3_bind_double(statement_, index, value); }
  // Binds ?1, ?2, ... to `values` in order, so that no parameter number is written by hand.
  template <typename... Values>
  void BindAll(const Values&... values) {
    int index = 0;
    (Bind(++index, values), ...);
  }
  std::string Text(int column) {
    const auto* text = sqlite3_column_text(statement_, column);
    return text ? reinterpret_cast<const char*>(text) : "";
  }

 private:
  sqlite3_stmt* statement_ = nullptr;
  int rc_ = SQLITE_ERROR;
};

Error SqlError(sqlite3* db, const std::string& path, const std::string& what) {
  return Error{path + ": " + what + ": " + sqlite3_errmsg(db)};
}

}  // namespace

Expected<std::unique_ptr<History>> History::Open(const std::string& path, bool read_only,
                                                 std::int64_t requests_kept) {
  sqlite3* db = nullptr;
  const int flags = read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  if (sqlite3_open_v2(path.c_str(), &db, flags | SQLITE_OPEN_FULLMUTEX, nullptr) != SQLITE_OK) {
    Error error = SqlError(db, path, "cannot open the history");
    sqlite3_close(db);
    return error;
  }
  sqlite3_busy_timeout(db, 2000);
  std::unique_ptr<History> history(new History(path, db, requests_kept));
  if (!read_only) {
    // synchronous=FULL: a committed row survives a power loss, as the session files do.
    // cache_size: 256 KiB of page cache instead of SQLite's 2 MB. The daemon writes at the ends
    // of the requests table (new rows, the oldest trimmed), a few pages; with the default cache a
    // full table of 10,000 rows kept 1.25 MB of the daemon's memory, with this 0.28 MB.
    const auto status = history->Exec(
        "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA cache_size=-256;"
        "CREATE TABLE IF NOT EXISTS sessions (id TEXT PRIMARY KEY, started_utime INTEGER,"
        " ended_utime INTEGER, plan TEXT, requested_by TEXT, nonce TEXT, state TEXT, reason TEXT,"
        " rms_before REAL, rms_after REAL, iterations INTEGER, runtime REAL, model_id TEXT);"
        "CREATE TABLE IF NOT EXISTS requests (received_utime INTEGER, request_utime INTEGER,"
        " nonce TEXT, action INTEGER, requested_by TEXT, verdict TEXT, nonce_used INTEGER);"
        "CREATE TABLE IF NOT EXISTS model_events (utime INTEGER, event TEXT, model_id TEXT);"
        "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value INTEGER);");
    if (!status) return status.error();
    if (!history->HasSessionColumn("change")) {
      const auto added = history->Exec("ALTER TABLE sessions ADD COLUMN change TEXT DEFAULT ''");
      if (!added) return added.error();
    }
  }
  return history;
}

History::~History() { sqlite3_close(db_); }

Status History::Exec(const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    Error error{path_ + ": " + (message ? message : "SQL error")};
    sqlite3_free(message);
    return error;
  }
  return OkStatus();
}

bool History::HasSessionColumn(const char* column) {
  Statement s(db_, "SELECT 1 FROM pragma_table_info('sessions') WHERE name = ?1");
  if (!s.ok()) return false;
  s.Bind(1, std::string(column));
  return sqlite3_step(s.get()) == SQLITE_ROW;
}

Status History::UpsertSession(const SessionRecord& r) {
  Statement s(db_,
              "INSERT INTO sessions (id, started_utime, ended_utime, plan, requested_by, nonce,"
              " state, reason, rms_before, rms_after, iterations, runtime, model_id, change)"
              " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)"
              " ON CONFLICT(id) DO UPDATE SET ended_utime=?3, state=?7, reason=?8, rms_before=?9,"
              " rms_after=?10, iterations=?11, runtime=?12, model_id=?13, change=?14");
  if (!s.ok()) return SqlError(db_, path_, "cannot prepare the session update");
  s.BindAll(r.id, r.started_utime, r.ended_utime, r.plan, r.requested_by, r.nonce, r.state,
            r.reason, r.rms_before, r.rms_after, static_cast<std::int64_t>(r.iterations), r.runtime,
            r.model_id, r.change);
  if (sqlite3_step(s.get()) != SQLITE_DONE)
    return SqlError(db_, path_, "cannot record session " + r.id);
  return OkStatus();
}

Status History::LogRequest(std::int64_t received_utime, std::int64_t request_utime,
                           const std::string& nonce, int action, const std::string& requested_by,
                           const std::string& verdict, bool nonce_used) {
  return LogRequests({RequestRow{received_utime, request_utime, nonce, action, requested_by,
                                 verdict, nonce_used}});
}

Status History::LogRequests(const std::vector<RequestRow>& rows) {
  if (rows.empty()) return OkStatus();
  if (auto begun = Exec("BEGIN IMMEDIATE"); !begun) return begun;
  auto logged = InsertRequests(rows);
  if (logged) logged = TrimRequests();
  if (logged) logged = Exec("COMMIT");
  if (!logged) (void)Exec("ROLLBACK");
  return logged;
}

Status History::SetRequestVerdict(const std::string& nonce, const std::string& verdict) {
  Statement s(db_, "UPDATE requests SET verdict = ?1 WHERE nonce = ?2");
  if (!s.ok()) return SqlError(db_, path_, "cannot prepare the request update");
  s.Bind(1, verdict);
  s.Bind(2, nonce);
  if (sqlite3_step(s.get()) != SQLITE_DONE) return SqlError(db_, path_, "cannot update a request");
  return OkStatus();
}

Status History::InsertRequests(const std::vector<RequestRow>& rows) {
  Statement s(db_, "INSERT INTO requests VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  if (!s.ok()) return SqlError(db_, path_, "cannot prepare the request log");
  for (const RequestRow& row : rows) {
    sqlite3_reset(s.get());
    s.Bind(1, row.received_utime);
    s.Bind(2, row.request_utime);
    s.Bind(3, row.nonce);
    s.Bind(4, static_cast<std::int64_t>(row.action));
    s.Bind(5, row.requested_by);
    s.Bind(6, row.verdict);
    s.Bind(7, static_cast<std::int64_t>(row.nonce_used ? 1 : 0));
    if (sqlite3_step(s.get()) != SQLITE_DONE) return SqlError(db_, path_, "cannot log a request");
  }
  return OkStatus();
}

Status History::TrimRequests() {
  // The rows beyond the newest requests_kept go; the newest used nonce among them is remembered.
  Statement floor(
      db_,
      "INSERT INTO meta (key, value) SELECT 'nonces_forgotten_up_to', max(request_utime)"
      " FROM requests WHERE rowid <= (SELECT max(rowid) FROM requests) - ?1"
      " AND nonce_used = 1 HAVING max(request_utime) IS NOT NULL"
      " ON CONFLICT(key) DO UPDATE SET value = max(value, excluded.value)");
  if (!floor.ok()) return SqlError(db_, path_, "cannot prepare the request trim");
  floor.Bind(1, requests_kept_);
  if (sqlite3_step(floor.get()) != SQLITE_DONE)
    return SqlError(db_, path_, "cannot trim the requests");
  Statement trim(db_, "DELETE FROM requests WHERE rowid <= (SELECT max(rowid) FROM requests) - ?1");
  if (!trim.ok()) return SqlError(db_, path_, "cannot prepare the request trim");
  trim.Bind(1, requests_kept_);
  if (sqlite3_step(trim.get()) != SQLITE_DONE)
    return SqlError(db_, path_, "cannot trim the requests");
  return OkStatus();
}

Expected<std::int64_t> History::ForgottenNoncesUpTo() {
  Statement s(db_, "SELECT value FROM meta WHERE key = 'nonces_forgotten_up_to'");
  if (!s.ok()) return SqlError(db_, path_, "cannot read the forgotten nonces");
  const int rc = sqlite3_step(s.get());
  if (rc == SQLITE_ROW) return static_cast<std::int64_t>(sqlite3_column_int64(s.get(), 0));
  if (rc != SQLITE_DONE) return SqlError(db_, path_, "cannot read the forgotten nonces");
  return std::numeric_limits<std::int64_t>::min();
}

std::uint64_t History::FileBytes() const {
  std::uint64_t total = 0;
  for (const char* suffix : {"", "-wal", "-shm"}) {
    std::error_code error;
    const auto size = std::filesystem::file_size(path_ + suffix, error);
    if (!error) total += size;
  }
  return total;
}

Status History::LogModelEvent(std::int64_t utime, const std::string& event,
                              const std::string& model_id) {
  Statement s(db_, "INSERT INTO model_events VALUES (?1, ?2, ?3)");
  if (!s.ok()) return SqlError(db_, path_, "cannot prepare the model event");
  s.Bind(1, utime);
  s.Bind(2, event);
  s.Bind(3, model_id);
  if (sqlite3_step(s.get()) != SQLITE_DONE) return SqlError(db_, path_, "cannot log a model event");
  return OkStatus();
}

Expected<std::vector<SessionRecord>> History::Sessions(int limit) {
  // A history that an older daemon wrote and no newer one opened for writing has no `change`.
  const std::string sql = std::string(
                              "SELECT id, started_utime, ended_utime, plan, requested_by, nonce,"
                              " state, reason, rms_before, rms_after, iterations, runtime,"
                              " model_id, ") +
                          (HasSessionColumn("change") ? "change" : "''") +
                          " FROM sessions ORDER BY started_utime DESC LIMIT ?1";
  Statement s(db_, sql.c_str());
  if (!s.ok()) return SqlError(db_, path_, "cannot read the sessions");
  s.Bind(1, static_cast<std::int64_t>(limit));
  std::vector<SessionRecord> records;
  int rc;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
    SessionRecord r;
    r.id = s.Text(0);
    r.started_utime = sqlite3_column_int64(s.get(), 1);
    r.ended_utime = sqlite3_column_int64(s.get(), 2);
    r.plan = s.Text(3);
    r.requested_by = s.Text(4);
    r.nonce = s.Text(5);
    r.state = s.Text(6);
    r.reason = s.Text(7);
    r.rms_before = sqlite3_column_double(s.get(), 8);
    r.rms_after = sqlite3_column_double(s.get(), 9);
    r.iterations = sqlite3_column_int(s.get(), 10);
    r.runtime = sqlite3_column_double(s.get(), 11);
    r.model_id = s.Text(12);
    r.change = s.Text(13);
    records.push_back(std::move(r));
  }
  if (rc != SQLITE_DONE) return SqlError(db_, path_, "cannot read the sessions");
  return records;
}

Expected<std::vector<std::pair<std::string, std::int64_t>>> History::NoncesSince(
    std::int64_t since_utime) {
  Statement s(
      db_,
      "SELECT nonce, request_utime FROM requests WHERE request_utime >= ?1 AND nonce_used = 1");
  if (!s.ok()) return SqlError(db_, path_, "cannot read the nonces");
  s.Bind(1, since_utime);
  std::vector<std::pair<std::string, std::int64_t>> nonces;
  int rc;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
    nonces.emplace_back(s.Text(0), sqlite3_column_int64(s.get(), 1));
  }
  if (rc != SQLITE_DONE) return SqlError(db_, path_, "cannot read the nonces");
  return nonces;
}

Expected<std::int64_t> History::RequestRows() {
  Statement s(db_, "SELECT count(*) FROM requests");
  if (!s.ok() || sqlite3_step(s.get()) != SQLITE_ROW) {
    return SqlError(db_, path_, "cannot count the requests");
  }
  return sqlite3_column_int64(s.get(), 0);
}

}  // namespace selfcal::daemon
