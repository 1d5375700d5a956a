#include "protocols/report/report.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <sstream>

#include "core/calib/validation_residuals.h"
#include "core/model/model_change.h"
#include "core/util/atomic_file.h"
#include "core/util/markup_text.h"
#include "protocols/report/json_text.h"
#include "protocols/report/report_data.h"
#include "protocols/report/report_page.h"

namespace selfcal::report {
namespace {

struct Library {
  const char* package;
  const char* script;   // below javascript_folder
  const char* licence;  // below licence_folder
};
constexpr Library kLibraries[] = {
    {"libjs-three", "three/three.min.js", "libjs-three/copyright"},
    {"libjs-three", "three/examples/js/controls/OrbitControls.js", nullptr},
    {"libjs-chart.js", "chart.js/chart.min.js", "libjs-chart.js/copyright"},
};

Status ReadLibraries(const ReportOptions& options, PageParts& parts) {
  parts.licences_html =
      "<h2>Licences</h2><p>This file contains three.js and Chart.js, from Debian's packages; their "
      "copyright files:</p>\n";
  for (const Library& library : kLibraries) {
    const std::string path = options.javascript_folder + "/" + library.script;
    const auto script = ReadFile(path);
    if (!script) {
      return Error{path + ": " + script.error().message + " (Debian package " + library.package +
                   ")"};
    }
    parts.libraries += *script + "\n";
    if (library.licence == nullptr) continue;
    const auto licence = ReadFile(options.licence_folder + "/" + library.licence);
    if (!licence)
      return Error{licence.error().message + " (Debian package " + library.package + ")"};
    parts.licences_html += std::string("<details><summary>") + library.package + "</summary><pre>" +
                           MarkupText(*licence) + "</pre></details>\n";
  }
  return OkStatus();
}

// The node at a dotted path of the result file ("change.findings.0.moved_deg"); an undefined
// node when there is none.
YAML::Node At(const YAML::Node& calibration, const std::string& key) {
  YAML::Node node = calibration;
  std::stringstream parts(key);
  try {
    for (std::string part; node && std::getline(parts, part, '.');) {
      const YAML::Node& parent = node;
      node.reset(parent.IsSequence() ? parent[std::stoul(part)] : parent[part]);
    }
  } catch (const std::exception&) {  // a scalar on the way, or a key that is not an index
    return YAML::Node(YAML::NodeType::Undefined);
  }
  return node;
}

// A number of the result file as the page shows it, tagged with its key for checking.
std::string Shown(const YAML::Node& calibration, const std::string& key, double scale, int decimals,
                  const char* unit) {
  const YAML::Node node = At(calibration, key);
  double value = std::nan("");
  try {
    if (node && node.IsScalar()) value = node.as<double>();
  } catch (const YAML::Exception&) {
  }
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value * scale);
  return "<span class=\"num\" data-key=\"" + key + "\" data-scale=\"" + JsonNumber(scale) +
         "\" data-decimals=\"" + std::to_string(decimals) + "\">" + text + "</span>" + unit;
}

std::string Text(const YAML::Node& calibration, const char* key) {
  const YAML::Node node = calibration[key];
  return node && node.IsScalar() ? MarkupText(node.as<std::string>()) : "(not in the result)";
}

std::string DecisionHtml(const GateSummary& gate) {
  std::string html = "<h2>Decision</h2>\n<p id=\"decision\" class=\"" +
                     std::string(gate.accepted ? "accepted" : "refused") + "\"><b>" +
                     (gate.accepted ? "ACCEPTED" : "REFUSED") + "</b>: " + MarkupText(gate.reason) +
                     "</p>\n<p>Acceptance gate of " + MarkupText(gate.configuration) +
                     ". Its rules, in the order it checks them, with this session's numbers:</p>\n"
                     "<table id=\"gate-rules\"><tr><th>rule</th><th>bound</th><th>this session</th>"
                     "</tr>\n";
  for (const GateRule& rule : gate.rules) {
    html += "<tr><td>" + MarkupText(rule.rule) + "</td><td>" + MarkupText(rule.limit) +
            "</td><td>" + MarkupText(rule.measured) + "</td></tr>\n";
  }
  return html + "</table>\n";
}

// A quick remastering's corrections per axis (`remaster:`, daemon/remaster.h), as a controller
// takes them; empty for a full calibration.
std::string RemasterText(const YAML::Node& c) {
  const YAML::Node remaster = c["remaster"];
  if (!remaster || !remaster["joint_offsets"] || !remaster["joint_offsets"].IsSequence()) return {};
  std::string text;
  char value[64];
  for (const YAML::Node& joint : remaster["joint_offsets"]) {
    const bool degrees = static_cast<bool>(joint["offset_deg"]);
    const YAML::Node offset = degrees ? joint["offset_deg"] : joint["offset_mm"];
    std::snprintf(value, sizeof value, " %+.4f %s", offset ? offset.as<double>(0) : std::nan(""),
                  degrees ? "deg" : "mm");
    text += (text.empty() ? "" : ", ") + MarkupText(joint["name"].as<std::string>("?")) + value;
  }
  return text + "; sensor mount " + Shown(c, "remaster.mount_shift_m", 1e3, 3, " mm, ") +
         Shown(c, "remaster.mount_turn_rad", 180 / M_PI, 4, " deg");
}

// One finding's numbers as calibration_yaml.cc writes them: each `name_deg` or `name_mm` with
// its `name_std_dev_deg` or `name_std_dev_mm` (null without a covariance).
std::string FindingNumbersHtml(const YAML::Node& c, const std::string& path) {
  std::string html;
  for (const auto& entry : At(c, path)) {
    const std::string key = entry.first.as<std::string>("");
    const std::string name = key.substr(0, key.rfind('_')), unit = key.substr(key.rfind('_') + 1);
    if ((unit != "deg" && unit != "mm") || name.find("_std_dev") != std::string::npos) continue;
    const std::string deviation = name + "_std_dev_" + unit, suffix = " " + unit;
    std::string words = name;
    std::replace(words.begin(), words.end(), '_', ' ');
    html += (html.empty() ? "" : ", ") + words + " " + Shown(c, path + "." + key, 1, 3, "") +
            (At(c, path + "." + deviation).IsNull()
                 ? suffix + " (no covariance)"
                 : " &plusmn; " + Shown(c, path + "." + deviation, 1, 3, suffix.c_str()));
  }
  return html;
}

// What changed against the old model, for the technician: the summary, each finding with its
// numbers and words, and what keeping the old model would cost.
std::string WhatChangedHtml(const YAML::Node& c) {
  std::string html = "<h2>What changed</h2>\n";
  const YAML::Node findings = At(c, "change.findings");
  if (!At(c, "change.summary")) return html + "<p>(not in the result)</p>\n";
  html += "<p id=\"change-summary\"><b>" + Text(c["change"], "summary") + "</b></p>\n";
  if (findings.IsSequence() && findings.size() > 0) {
    html +=
        "<table id=\"change-findings\"><tr><th>what</th><th>change &plusmn; standard deviation"
        "</th><th>in words</th></tr>\n";
    for (std::size_t i = 0; i < findings.size(); ++i) {
      if (!findings[i].IsMap()) continue;
      const auto kind = kChangeKindNames.Parse(findings[i]["kind"].as<std::string>(""));
      const std::string what =
          kind == ChangeKind::kJointZero
              ? "joint " + findings[i]["joint"].as<std::string>("?") + " zero offset"
          : kind == ChangeKind::kSensorMount ? std::string("sensor mount")
                                             : std::string("link geometry");
      html += "<tr><td>" + MarkupText(what) + "</td><td>" +
              FindingNumbersHtml(c, "change.findings." + std::to_string(i)) + "</td><td>" +
              MarkupText(findings[i]["text"].as<std::string>("")) + "</td></tr>\n";
    }
    html +=
        "</table>\n<p>The standard deviation is that of what the comparison shows with nothing "
        "changed, from the calibration's covariance.</p>\n";
  }
  const std::string kept = "change.keeping_the_start_model.";
  return html + "<p id=\"change-kept\">Had the old model been kept, the position error would be " +
         Shown(c, kept + "sensor.rms_position_m", 1e3, 3, " mm RMS (") +
         Shown(c, kept + "sensor.max_position_m", 1e3, 3, " mm at most) at the sensor and ") +
         Shown(c, kept + "flange.rms_position_m", 1e3, 3, " mm RMS (") +
         Shown(c, kept + "flange.max_position_m", 1e3, 3,
               " mm at most) at the flange, the new model taken as the truth.</p>\n");
}

std::string SummaryHtml(const ReportInput& input, const YAML::Node& c) {
  std::string html = "<h2>Result</h2>\n<table id=\"summary\">\n";
  const auto row = [&](const char* what, const std::string& value) {
    html += std::string("<tr><th>") + what + "</th><td>" + value + "</td></tr>\n";
  };
  row("termination", Text(c, "termination") + " (" + Text(c, "message") + ")");
  row("converged, usable", Text(c, "converged") + ", " + Text(c, "usable"));
  row("validation RMS, old model", Shown(c, "validation.rms_before_m", 1e3, 4, " mm"));
  row("validation RMS, new model", Shown(c, "validation.rms_after_m", 1e3, 4, " mm"));
  row("validation matches, old model", Shown(c, "validation.matches_before", 1, 0, ""));
  row("validation matches, new model", Shown(c, "validation.matches_after", 1, 0, ""));
  if (At(c, "validation.held_out_registration.scans").size() > 0) {
    row("held-out scans registered onto the fit scans: their sensor origins moved",
        Shown(c, "validation.held_out_registration.rms_position_m", 1e3, 4, " mm RMS, worst ") +
            Shown(c, "validation.held_out_registration.worst_position_m", 1e3, 4, " mm"));
  }
  row("ICP iterations", Shown(c, "iterations", 1, 0, ""));
  row("runtime", Shown(c, "runtime_s", 1, 3, " s"));
  row("fit scans, validation scans",
      Shown(c, "fit_scans", 1, 0, ", ") + Shown(c, "validation_scans", 1, 0, ""));
  row("points", Shown(c, "points", 1, 0, ""));
  row("old model", MarkupText(input.before_name));
  row("new model", MarkupText(input.after_name));
  if (const std::string remaster = RemasterText(c); !remaster.empty()) {
    row("zero offsets to add to the measured joint positions (quick remastering)", remaster);
  }
  row("recording", MarkupText(input.recording_name));
  row("software", MarkupText(input.software) + " (report); result by " + Text(c, "software"));
  return html + "</table>\n";
}

std::string SectionsHtml(const ReportInput& input, const YAML::Node& c, std::size_t shown,
                         std::size_t valid) {
  std::string html = "<h2>Validation scans fused with the old and the new model</h2>\n<p>" +
                     std::to_string(shown) + " of " + std::to_string(valid) +
                     " valid points of the held-out scans per model, one colour per scan. Drag "
                     "to turn, wheel to zoom, right-drag to pan; both views share the camera. "
                     "With a good model the scans of one surface lie on each other.</p>\n"
                     "<div class=\"views\"><div class=\"view\"><b>old model</b> (" +
                     MarkupText(input.before_name) +
                     ")<br><canvas id=\"view-before\" width=\"620\" height=\"480\"></canvas></div>"
                     "<div class=\"view\"><b>new model</b> (" +
                     MarkupText(input.after_name) +
                     ")<br><canvas id=\"view-after\" width=\"620\" height=\"480\"></canvas></div>"
                     "</div>\n<h2>Plots</h2>\n<div class=\"plots\">";
  for (const char* id : {"plot-residuals", "plot-convergence", "plot-coverage", "plot-error-map",
                         "plot-angles", "plot-translations"}) {
    html += std::string("<div class=\"plot\"><canvas id=\"") + id +
            "\" width=\"620\" height=\"340\"></canvas></div>";
  }
  html +=
      "</div>\n<h2>Parameters</h2>\n<table><thead><tr><th>parameter</th><th>old</th>"
      "<th>new</th><th>standard deviation</th><th>change</th></tr></thead><tbody "
      "id=\"parameter-rows\"></tbody></table>\n<p>Values in rad and m, as in the result "
      "file.</p>\n<p>Poorly observable: ";
  const YAML::Node poorly = c["poorly_observable"];
  html += poorly && poorly.size() > 0 ? "" : "none";
  for (std::size_t i = 0; poorly && i < poorly.size(); ++i) {
    html += i ? "; " : "";
    html += MarkupText(poorly[i].as<std::string>());
  }
  html +=
      "</p>\n<h2>Iterations</h2>\n<table><thead><tr><th>iteration</th><th>matches</th>"
      "<th>RMS before [mm]</th><th>RMS after [mm]</th><th>|delta k|</th>"
      "<th>step (stopped on)</th><th>LM steps</th>"
      "<th>time [s]</th></tr></thead><tbody id=\"iteration-rows\"></tbody></table>\n";
  return html + "<h2>How to roll back</h2>\n<p id=\"rollback\">" + MarkupText(input.rollback) +
         "</p>\n";
}

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &utc);
  return text;
}

}  // namespace

Expected<std::string> FormatReport(const ReportInput& input, const ReportOptions& options) {
  YAML::Node calibration;
  try {
    calibration = YAML::Load(input.calibration_yaml);
  } catch (const YAML::Exception& e) {
    return Error{"the result's calibration section: " + std::string(e.what())};
  }
  if (!calibration.IsMap()) return Error{"the result has no calibration section (a mapping)"};
  PageParts parts;
  parts.title = "selfcal report: " + input.title;
  if (auto read = ReadLibraries(options, parts); !read) return read.error();

  const double scale = calibration["scale_m"] ? calibration["scale_m"].as<double>(0) : 0;
  const auto before =
      calib::ValidationResiduals(input.datasets, input.before, input.options, scale);
  const auto after = calib::ValidationResiduals(input.datasets, input.after, input.options, scale);
  std::size_t valid = 0;
  for (const auto& dataset : input.datasets)
    valid += dataset.validation ? dataset.ValidPointCount() : 0;
  parts.data_json =
      IterationsJson(calibration) + ", " + ParametersJson(calibration) + ", " +
      ErrorMapJson(calibration) + ", " + HistogramJson(before, after, input.options.d_max) + ", " +
      CoverageJson(input.datasets, input.after) + ", " +
      CloudsJson(input.datasets, input.before, input.after, options.max_points_per_model);
  const std::size_t shown =
      std::min(valid, options.max_points_per_model == 0 ? valid : options.max_points_per_model);
  parts.body_html = "<h1>" + MarkupText(parts.title) + "</h1>\n<p>Written " + UtcNow() + " by " +
                    MarkupText(input.software) + ".</p>\n<p id=\"problems\"></p>\n" +
                    DecisionHtml(input.gate) + WhatChangedHtml(calibration) +
                    SummaryHtml(input, calibration) +
                    SectionsHtml(input, calibration, shown, valid);
  return RenderPage(parts);
}

Status WriteReport(const std::string& path, const ReportInput& input,
                   const ReportOptions& options) {
  const auto page = FormatReport(input, options);
  if (!page) return page.error();
  return WriteFileAtomically(path, *page);
}

Status LoadRecordingInto(ReportInput& input, const std::string& recording_path,
                         const SensorConfig& sensor, const recording::RecordingOptions& options) {
  auto datasets = recording::LoadRecording(recording_path, input.before, sensor, options);
  if (!datasets) return datasets.error();
  input.datasets = std::move(*datasets);
  input.options = recording::CalibrationOptionsFromSensor(sensor);
  input.recording_name = recording_path;
  return OkStatus();
}

}  // namespace selfcal::report
