#include "tools/selfcal/history_export.h"

#include <libpq-fe.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "daemon/history.h"

namespace selfcal::cli {
namespace {

// Shown in docs/daemon.md ("Fleet history in PostgreSQL"); a test checks that both agree.
constexpr const char* kSchema = R"sql(CREATE TABLE IF NOT EXISTS selfcal_robots (
  robot_id text PRIMARY KEY
);
CREATE TABLE IF NOT EXISTS selfcal_sessions (
  robot_id text NOT NULL REFERENCES selfcal_robots,
  session_id text NOT NULL,
  started timestamptz NOT NULL,
  ended timestamptz,
  plan text NOT NULL,
  requested_by text NOT NULL,
  state text NOT NULL,
  reason text NOT NULL,
  validation_rms_before_m double precision,
  validation_rms_after_m double precision,
  iterations integer NOT NULL,
  runtime_s double precision NOT NULL,
  model_id text NOT NULL,
  change text NOT NULL,
  PRIMARY KEY (robot_id, session_id)
);
CREATE TABLE IF NOT EXISTS selfcal_results (
  robot_id text NOT NULL,
  session_id text NOT NULL,
  model_id text NOT NULL,
  software text NOT NULL,
  termination text NOT NULL,
  fit_scans integer,
  validation_scans integer,
  predicted_sensor_rms_position_m double precision,
  PRIMARY KEY (robot_id, session_id),
  FOREIGN KEY (robot_id, session_id) REFERENCES selfcal_sessions
);
CREATE TABLE IF NOT EXISTS selfcal_parameter_values (
  robot_id text NOT NULL,
  session_id text NOT NULL,
  name text NOT NULL,
  unit text NOT NULL,
  nominal double precision NOT NULL,
  calibrated double precision NOT NULL,
  std_dev double precision,
  PRIMARY KEY (robot_id, session_id, name),
  FOREIGN KEY (robot_id, session_id) REFERENCES selfcal_results
);
)sql";

// States a session does not leave once it has reached them (daemon/sessions.h).
bool IsFinal(const std::string& state) {
  static const std::set<std::string> kFinal = {"accepted", "rejected", "aborted", "failed",
                                               "incomplete"};
  return kFinal.count(state) > 0;
}

using Connection = std::unique_ptr<PGconn, decltype(&PQfinish)>;
using Result = std::unique_ptr<PGresult, decltype(&PQclear)>;

// A statement's result, or an error that names what it was doing.
Expected<Result> Checked(PGresult* raw, const std::string& what) {
  Result result(raw, &PQclear);
  const ExecStatusType status = PQresultStatus(result.get());
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) {
    return Error{"PostgreSQL: cannot " + what + ": " + PQresultErrorMessage(result.get())};
  }
  return result;
}

// One statement with text parameters (nullopt = SQL NULL).
Expected<Result> Run(PGconn* db, const std::string& what, const char* sql,
                     const std::vector<std::optional<std::string>>& parameters = {}) {
  std::vector<const char*> values;
  for (const auto& p : parameters) values.push_back(p ? p->c_str() : nullptr);
  return Checked(PQexecParams(db, sql, static_cast<int>(values.size()), nullptr, values.data(),
                              nullptr, nullptr, 0),
                 what);
}

// Several statements without parameters (the schema; PQexecParams takes only one).
Expected<Result> RunScript(PGconn* db, const std::string& what, const std::string& sql) {
  return Checked(PQexec(db, sql.c_str()), what);
}

std::string Text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}
std::optional<std::string> MetresOrNull(double value) {
  return value >= 0 ? std::optional<std::string>(Text(value)) : std::nullopt;
}
std::string Seconds(std::int64_t utime) { return Text(static_cast<double>(utime) * 1e-6); }

// The exported state of each of the robot's sessions.
Expected<std::map<std::string, std::string>> ExportedStates(PGconn* db,
                                                            const std::string& robot_id) {
  auto rows = Run(db, "read the exported sessions",
                  "SELECT session_id, state FROM selfcal_sessions WHERE robot_id = $1", {robot_id});
  if (!rows) return rows.error();
  std::map<std::string, std::string> states;
  for (int i = 0; i < PQntuples(rows->get()); ++i) {
    states[PQgetvalue(rows->get(), i, 0)] = PQgetvalue(rows->get(), i, 1);
  }
  return states;
}

// Inserts or updates one session; true when it was new.
Expected<bool> UpsertSession(PGconn* db, const std::string& robot_id,
                             const daemon::SessionRecord& s) {
  auto row =
      Run(db, "write session " + s.id,
          "INSERT INTO selfcal_sessions VALUES ($1, $2, to_timestamp($3::double precision),"
          " to_timestamp($4::double precision), $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)"
          " ON CONFLICT (robot_id, session_id) DO UPDATE SET ended = EXCLUDED.ended,"
          " state = EXCLUDED.state, reason = EXCLUDED.reason,"
          " validation_rms_before_m = EXCLUDED.validation_rms_before_m,"
          " validation_rms_after_m = EXCLUDED.validation_rms_after_m,"
          " iterations = EXCLUDED.iterations, runtime_s = EXCLUDED.runtime_s,"
          " model_id = EXCLUDED.model_id, change = EXCLUDED.change RETURNING (xmax = 0)",
          {robot_id, s.id, Seconds(s.started_utime),
           s.ended_utime > 0 ? std::optional<std::string>(Seconds(s.ended_utime)) : std::nullopt,
           s.plan, s.requested_by, s.state, s.reason, MetresOrNull(s.rms_before),
           MetresOrNull(s.rms_after), std::to_string(s.iterations), Text(s.runtime), s.model_id,
           s.change});
  if (!row) return row.error();
  return std::string(PQgetvalue(row->get(), 0, 0)) == "t";
}

std::optional<std::string> NumberOrNull(const YAML::Node& node) {
  if (!node || !node.IsScalar()) return std::nullopt;
  return Text(node.as<double>());
}

// The result of an accepted session and its parameter values, from its model's `calibration:`
// section (docs/formats.md).
Status InsertResult(PGconn* db, const std::string& robot_id, const daemon::SessionRecord& s,
                    const YAML::Node& calibration, ExportSummary& summary) {
  const YAML::Node predicted = calibration["predicted_error"]["sensor"]["rms_position_m"];
  auto result =
      Run(db, "write the result of session " + s.id,
          "INSERT INTO selfcal_results VALUES ($1, $2, $3, $4, $5, $6, $7, $8)"
          " ON CONFLICT DO NOTHING",
          {robot_id, s.id, s.model_id, calibration["software"].as<std::string>(""),
           calibration["termination"].as<std::string>(""), NumberOrNull(calibration["fit_scans"]),
           NumberOrNull(calibration["validation_scans"]), NumberOrNull(predicted)});
  if (!result) return result.error();
  summary.results_added += std::atoi(PQcmdTuples(result->get()));
  for (const YAML::Node& p : calibration["parameters"]) {
    const std::string unit = p["nominal_m"] ? "m" : "rad";
    auto value =
        Run(db, "write the parameters of session " + s.id,
            "INSERT INTO selfcal_parameter_values VALUES ($1, $2, $3, $4, $5, $6, $7)"
            " ON CONFLICT DO NOTHING",
            {robot_id, s.id, p["name"].as<std::string>(), unit, NumberOrNull(p["nominal_" + unit]),
             NumberOrNull(p["calibrated_" + unit]), NumberOrNull(p["std_dev_" + unit])});
    if (!value) return value.error();
    summary.parameters_added += std::atoi(PQcmdTuples(value->get()));
  }
  return OkStatus();
}

// The calibration section of an accepted session's model, or a null node when the model is gone.
Expected<YAML::Node> CalibrationOf(const std::string& storage_folder,
                                   const daemon::SessionRecord& s) {
  const std::string path = storage_folder + "/models/" + s.model_id + "/model.yaml";
  if (!std::filesystem::exists(path)) return YAML::Node();
  try {
    const YAML::Node calibration = YAML::LoadFile(path)["calibration"];
    if (!calibration || !calibration["parameters"].IsSequence()) {
      return Error{path + ": no calibration section with parameters"};
    }
    return calibration;
  } catch (const YAML::Exception& e) {
    return Error{path + ": " + e.what()};
  }
}

Status ExportSession(PGconn* db, const std::string& storage_folder, const std::string& robot_id,
                     const daemon::SessionRecord& s, ExportSummary& summary) {
  auto added = UpsertSession(db, robot_id, s);
  if (!added) return added.error();
  ++(*added ? summary.sessions_added : summary.sessions_updated);
  if (s.state != "accepted" || s.model_id.empty()) return OkStatus();
  auto calibration = CalibrationOf(storage_folder, s);
  if (!calibration) return calibration.error();
  if (!*calibration) {
    ++summary.models_missing;
    return OkStatus();
  }
  return InsertResult(db, robot_id, s, *calibration, summary);
}

Expected<Connection> Connect(const std::string& conninfo) {
  Connection db(PQconnectdb(conninfo.c_str()), &PQfinish);
  if (!db || PQstatus(db.get()) != CONNECTION_OK) {
    // libpq's message names the server and the reason, never the password.
    return Error{std::string("cannot connect to PostgreSQL: ") +
                 (db ? PQerrorMessage(db.get()) : "out of memory")};
  }
  return db;
}

}  // namespace

const char* FleetSchemaSql() { return kSchema; }

Expected<ExportSummary> ExportHistory(const std::string& storage_folder,
                                      const std::string& robot_id, const std::string& conninfo) {
  auto history = daemon::History::Open(storage_folder + "/history.sqlite", /*read_only=*/true);
  if (!history) return history.error();
  auto sessions = (*history)->Sessions(std::numeric_limits<int>::max());
  if (!sessions) return sessions.error();
  auto db = Connect(conninfo);
  if (!db) return db.error();
  PGconn* connection = db->get();
  if (auto done = RunScript(connection, "create the tables", std::string("BEGIN;\n") + kSchema);
      !done) {
    return done.error();
  }
  if (auto robot = Run(connection, "write the robot",
                       "INSERT INTO selfcal_robots VALUES ($1) ON CONFLICT DO NOTHING", {robot_id});
      !robot) {
    return robot.error();
  }
  auto exported = ExportedStates(connection, robot_id);
  if (!exported) return exported.error();
  ExportSummary summary;
  for (auto it = sessions->rbegin(); it != sessions->rend(); ++it) {  // oldest first
    const auto known = exported->find(it->id);
    if (known != exported->end() && known->second == it->state && IsFinal(it->state)) {
      ++summary.sessions_unchanged;
      continue;
    }
    auto status = ExportSession(connection, storage_folder, robot_id, *it, summary);
    if (!status) return status.error();  // the connection closes: PostgreSQL rolls back
  }
  if (auto done = Run(connection, "commit", "COMMIT"); !done) return done.error();
  return summary;
}

}  // namespace selfcal::cli
