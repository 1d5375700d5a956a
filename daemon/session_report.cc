#include "daemon/session_report.h"

#include <yaml-cpp/yaml.h>

#include "daemon/gate_rules.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "protocols/report/report.h"

namespace selfcal::daemon {
namespace {

std::string Rollback(const SessionReport& session) {
  if (!session.decision.accepted) {
    return "Nothing was installed: the current model " + session.current_id +
           " stays. There is nothing to roll back.";
  }
  return "Installed as models/" + session.session_id + ". To go back to " + session.current_id +
         ": `selfcal rollback --by NAME` (a signed ROLLBACK request, docs/daemon.md) makes the "
         "previous model current again; the history keeps both.";
}

}  // namespace

Status WriteSessionReport(const DaemonConfig& config, const SessionReport& session) {
  const auto sensor = ReadSensorConfig(config.sensor);
  if (!sensor) return sensor.error();
  report::ReportInput input;
  input.title = "session " + session.session_id;
  input.software = std::string("selfcald ") + SELFCAL_VERSION;
  input.before_name = "models/" + session.current_id;
  input.after_name = "the result of session " + session.session_id;
  input.before = session.current;
  input.after = session.result.model;
  input.calibration_yaml = session.result.calibration_yaml;
  recording::RecordingOptions options;
  options.channels.joint_state = config.channels.joint_state;
  options.channels.scan_marker = config.channels.scan_marker;
  options.SetSensorChannel(sensor->layout, config.channels.sensor);
  if (auto loaded = report::LoadRecordingInto(input, session.recording_path, *sensor, options);
      !loaded) {
    return loaded;
  }
  input.gate = {session.decision.accepted, session.decision.reason, config.path,
                DescribeGateRules(config.acceptance, session.current, session.result)};
  input.rollback = Rollback(session);
  return report::WriteReport(session.path, input);
}

}  // namespace selfcal::daemon
