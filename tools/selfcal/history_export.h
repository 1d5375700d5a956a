// `selfcal history export`: copies selfcald's history into PostgreSQL, where the engineers who
// look after many robots query them together (docs/daemon.md, "Fleet history in PostgreSQL").
// Sessions, the results of accepted sessions and their calibrated parameter values, every row
// keyed by the robot id. Incremental and idempotent: a session already exported in a final state
// is skipped, one that changed since is updated, and a second run adds nothing.
#pragma once

#include <string>

#include "core/util/expected.h"

namespace selfcal::cli {

struct ExportSummary {
  int sessions_added = 0;
  int sessions_updated = 0;
  int sessions_unchanged = 0;  // already exported in a final state: not sent again
  int results_added = 0;
  int parameters_added = 0;
  int models_missing = 0;  // accepted sessions whose model folder is gone: no result exported
};

// The tables `selfcal history export` creates when missing (CREATE TABLE IF NOT EXISTS).
const char* FleetSchemaSql();

// Exports `storage_folder`'s history (history.sqlite, models/<id>/model.yaml) as `robot_id` to
// the database `conninfo` names (a libpq connection string or postgresql:// URI), in one
// transaction: on any error nothing of this run is kept.
Expected<ExportSummary> ExportHistory(const std::string& storage_folder,
                                      const std::string& robot_id, const std::string& conninfo);

}  // namespace selfcal::cli
