// `selfcal history export` against a real PostgreSQL server that the test starts in a temporary
// folder (Unix socket only: no TCP port is opened), from a daemon storage written through the
// daemon's own History and ModelStore.
#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <pwd.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "daemon/history.h"
#include "daemon/model_store.h"

namespace selfcal {
namespace {

namespace fs = std::filesystem;

struct Output {
  int code = -1;
  std::string text;
};
Output Capture(const std::string& command) {
  Output out;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe)) out.text += buffer;
  const int status = pclose(pipe);
  out.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

std::string MakeTempFolder(const char* name) {
  std::string pattern = "/tmp/" + std::string(name) + "-XXXXXX";
  const char* made = mkdtemp(pattern.data());
  return made ? made : "";
}

// A PostgreSQL server of its own (initdb + pg_ctl). PostgreSQL refuses to run as root: as root
// the server runs as the `postgres` user the Debian package creates.
class PostgresServer {
 public:
  bool Start(std::string* error) {
    folder_ = MakeTempFolder("selfcal-pg");
    if (folder_.empty()) return Fail("mkdtemp failed", error);
    if (geteuid() == 0) {
      const passwd* user = getpwnam("postgres");
      if (!user) return Fail("no `postgres` user (tools/setup-deps installs postgresql)", error);
      if (chown(folder_.c_str(), user->pw_uid, user->pw_gid) != 0) return Fail("chown", error);
      as_user_ = "runuser -u postgres -- ";
    }
    const std::string bin = PG_BINDIR;
    const Output init = Capture(
        as_user_ + bin + "/initdb --no-sync -A trust -U selfcal -E UTF8 -D " + folder_ + "/data");
    if (init.code != 0) return Fail("initdb: " + init.text, error);
    const Output start = Capture(as_user_ + bin + "/pg_ctl -w -t 60 -D " + folder_ + "/data -l " +
                                 folder_ + "/server.log -o \"-c listen_addresses='' -k " + folder_ +
                                 " -p 54329 -c fsync=off\" start");
    if (start.code != 0) return Fail("pg_ctl start: " + start.text, error);
    started_ = true;
    return true;
  }
  ~PostgresServer() {
    if (started_) Capture(as_user_ + PG_BINDIR + "/pg_ctl -w -m fast -D " + folder_ + "/data stop");
    if (!folder_.empty()) fs::remove_all(folder_);
  }
  std::string Url() const {
    return "postgresql:///postgres?host=" + folder_ + "&port=54329&user=selfcal";
  }

 private:
  static bool Fail(const std::string& message, std::string* error) {
    *error = message;
    return false;
  }
  std::string folder_, as_user_;
  bool started_ = false;
};

long long Count(const std::string& url, const std::string& sql) {
  PGconn* db = PQconnectdb(url.c_str());
  long long count = -1;
  if (PQstatus(db) == CONNECTION_OK) {
    PGresult* result = PQexec(db, sql.c_str());
    if (PQresultStatus(result) == PGRES_TUPLES_OK && PQntuples(result) == 1) {
      count = std::atoll(PQgetvalue(result, 0, 0));
    } else {
      ADD_FAILURE() << sql << ": " << PQresultErrorMessage(result);
    }
    PQclear(result);
  } else {
    ADD_FAILURE() << PQerrorMessage(db);
  }
  PQfinish(db);
  return count;
}

daemon::SessionRecord Session(const std::string& id, std::int64_t started_s,
                              const std::string& state, const std::string& model_id = "") {
  daemon::SessionRecord s;
  s.id = id;
  s.started_utime = started_s * 1'000'000;
  s.ended_utime = s.started_utime + 300'000'000;
  s.plan = "quick";
  s.requested_by = "technician";
  s.state = state;
  s.reason = state == "rejected" ? "validation RMS worse" : "";
  s.rms_before = 0.0021;
  s.rms_after = state == "calibrating" ? -1 : 0.0009;
  s.model_id = model_id;
  s.change = state == "accepted" ? "joint A4 zero offset moved 0.410 deg (mastering lost?)" : "";
  return s;
}

// A result's calibration section as the daemon installs it (docs/formats.md), two parameters.
std::string CalibrationYaml(double beta) {
  std::ostringstream out;
  out << "software: selfcal 0.1.0\ntermination: converged\nfit_scans: 28\nvalidation_scans: 7\n"
         "predicted_error: {sensor: {rms_position_m: 0.0012}}\nparameters:\n"
         "  - {name: A3->A4.beta, nominal_rad: 0, calibrated_rad: "
      << beta
      << ", std_dev_rad: 0.0001}\n"
         "  - {name: A3->A4.y, nominal_m: 0.42, calibrated_m: 0.4213, std_dev_m: 0.0002}\n";
  return out.str();
}

class HistoryExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string error;
    ASSERT_TRUE(server_.Start(&error)) << error;
    storage_ = MakeTempFolder("selfcal-storage");
    ASSERT_FALSE(storage_.empty());
    const std::string nominal =
        std::string(std::getenv("SELFCAL_SOURCE_DIR")) + "/config/robots/kuka_lbr_iiwa_r840.yaml";
    auto store = daemon::ModelStore::Open(storage_, nominal, [](const RobotModel&) {
      return Expected<std::string>(std::string("<robot name=\"test\"/>\n"));
    });
    ASSERT_TRUE(store) << store.error().message;
    store_.emplace(std::move(*store));
    auto history = daemon::History::Open(storage_ + "/history.sqlite", /*read_only=*/false);
    ASSERT_TRUE(history) << history.error().message;
    history_ = std::move(*history);
  }
  void TearDown() override {
    history_.reset();
    if (!storage_.empty()) fs::remove_all(storage_);
  }
  void Accept(const std::string& id, std::int64_t started_s, const std::string& model_id,
              double beta) {
    auto current = store_->Current();
    ASSERT_TRUE(current) << current.error().message;
    ASSERT_TRUE(store_->Install(model_id, current->model, CalibrationYaml(beta)));
    ASSERT_TRUE(history_->UpsertSession(Session(id, started_s, "accepted", model_id)));
  }
  Output Export(const std::string& robot_id, const std::string& url) {
    return Capture(std::string(SELFCAL_BINARY) + " history export --storage " + storage_ +
                   " --robot-id " + robot_id + " --to '" + url + "'");
  }
  long long Rows(const std::string& table) {
    return Count(server_.Url(), "SELECT count(*) FROM " + table);
  }

  PostgresServer server_;
  std::string storage_;
  std::optional<daemon::ModelStore> store_;
  std::unique_ptr<daemon::History> history_;
};

TEST_F(HistoryExportTest, CopiesSessionsResultsAndParametersOnceAndThenOnlyWhatChanged) {
  Accept("20261101T080000Z", 1'793'520'000, "m1", 0.0010);
  ASSERT_TRUE(history_->UpsertSession(Session("20261102T080000Z", 1'793'606'400, "rejected")));
  ASSERT_TRUE(history_->UpsertSession(Session("20261201T080000Z", 1'796'112'000, "calibrating")));

  const Output first = Export("cell-7", server_.Url());
  ASSERT_EQ(first.code, 0) << first.text;
  EXPECT_NE(first.text.find("robot cell-7: 3 sessions added, 0 updated, 0 unchanged; 1 results "
                            "and 2 parameter values added"),
            std::string::npos)
      << first.text;
  EXPECT_EQ(Rows("selfcal_robots"), 1);
  EXPECT_EQ(Rows("selfcal_sessions"), 3);
  EXPECT_EQ(Rows("selfcal_results"), 1);
  EXPECT_EQ(Rows("selfcal_parameter_values"), 2);

  // Again: nothing new, the session still calibrating is sent again but changes nothing.
  const Output again = Export("cell-7", server_.Url());
  ASSERT_EQ(again.code, 0) << again.text;
  EXPECT_NE(again.text.find("0 sessions added, 1 updated, 2 unchanged; 0 results and 0 parameter"),
            std::string::npos)
      << again.text;
  EXPECT_EQ(Rows("selfcal_sessions"), 3);
  EXPECT_EQ(Rows("selfcal_parameter_values"), 2);

  // The calibrating session ends accepted, a new one is rejected: one added, one updated.
  Accept("20261201T080000Z", 1'796'112'000, "m2", 0.0014);
  ASSERT_TRUE(history_->UpsertSession(Session("20261202T080000Z", 1'796'198'400, "rejected")));
  const Output third = Export("cell-7", server_.Url());
  ASSERT_EQ(third.code, 0) << third.text;
  EXPECT_NE(third.text.find("1 sessions added, 1 updated, 2 unchanged; 1 results and 2 parameter"),
            std::string::npos)
      << third.text;
  EXPECT_EQ(Rows("selfcal_sessions"), 4);
  EXPECT_EQ(Rows("selfcal_results"), 2);
  EXPECT_EQ(Rows("selfcal_parameter_values"), 4);
  EXPECT_EQ(Count(server_.Url(),
                  "SELECT count(*) FROM selfcal_sessions WHERE state = 'accepted'"
                  " AND session_id = '20261201T080000Z' AND validation_rms_after_m = 0.0009"
                  " AND change LIKE 'joint A4 zero offset moved%'"),
            1);

  // A second robot with the same session ids: the robot id keys every row.
  const Output other = Export("cell-8", server_.Url());
  ASSERT_EQ(other.code, 0) << other.text;
  EXPECT_EQ(Rows("selfcal_robots"), 2);
  EXPECT_EQ(Rows("selfcal_sessions"), 8);
  EXPECT_EQ(Rows("selfcal_parameter_values"), 8);
}

std::string DocsBlock(const std::string& marker, const std::string& language) {
  std::ifstream docs(std::string(std::getenv("SELFCAL_SOURCE_DIR")) + "/docs/daemon.md");
  std::stringstream text;
  text << docs.rdbuf();
  const std::string all = text.str();
  std::smatch match;
  if (!std::regex_search(
          all, match, std::regex("<!-- " + marker + " -->\\s*```" + language + "\\n([^`]*)```"))) {
    ADD_FAILURE() << "docs/daemon.md has no block after <!-- " << marker << " -->";
    return "";
  }
  return match[1].str();
}

TEST(HistoryExportSchema, TheDocsShowTheSchemaTheExportCreates) {
  const Output schema = Capture(std::string(SELFCAL_BINARY) + " history export --schema");
  ASSERT_EQ(schema.code, 0) << schema.text;
  EXPECT_EQ(schema.text, DocsBlock("fleet schema", "sql"));
}

// The drift query of docs/daemon.md, run on what the export wrote.
TEST_F(HistoryExportTest, TheDocumentedDriftQueryRuns) {
  Accept("20261101T080000Z", 1'793'520'000, "m1", 0.0010);
  Accept("20261201T080000Z", 1'796'112'000, "m2", 0.0014);
  ASSERT_EQ(Export("cell-7", server_.Url()).code, 0);
  std::string query = DocsBlock("drift query", "sql");
  ASSERT_FALSE(query.empty());
  query = query.substr(0, query.find_last_of(';'));
  // Months with a value of the parameter for this robot: November and December.
  EXPECT_EQ(Count(server_.Url(),
                  "SELECT count(*) FROM (" + query + ") AS drift WHERE robot_id = 'cell-7'"),
            2);
}

TEST_F(HistoryExportTest, AnUnreachableDatabaseIsAClearErrorWithoutThePassword) {
  ASSERT_TRUE(history_->UpsertSession(Session("20261102T080000Z", 1'793'606'400, "rejected")));
  const Output out = Export(
      "cell-7", "postgresql://selfcal:s3cret@/postgres?host=/nonexistent-socket-dir&port=54329");
  EXPECT_NE(out.code, 0);
  EXPECT_NE(out.text.find("cannot connect to PostgreSQL"), std::string::npos) << out.text;
  EXPECT_EQ(out.text.find("s3cret"), std::string::npos) << out.text;
}

TEST_F(HistoryExportTest, ABadRobotIdIsRefusedBeforeConnecting) {
  const Output out = Export("'cell 7;'", server_.Url());
  EXPECT_NE(out.code, 0);
  EXPECT_NE(out.text.find("robot id must be 1 to 64"), std::string::npos) << out.text;
}

}  // namespace
}  // namespace selfcal
