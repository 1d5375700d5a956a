// `selfcal fk --robot MODEL.yaml --joints q1,q2,...`: prints T_base_sensor as a 4 x 4 matrix.
#include <spdlog/spdlog.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>

#include "core/model/kinematics.h"
#include "protocols/model_file/model_file.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {
namespace {

// Comma-separated numbers; the error names the position of the bad entry.
Expected<std::vector<double>> ParseJointList(const std::string& text) {
  std::vector<double> values;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    std::string item = text.substr(start, end - start);
    // Surrounding blanks are harmless ("0.1, 0.2").
    const auto first = item.find_first_not_of(" \t");
    const auto last = item.find_last_not_of(" \t");
    item = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size()) {
      return Error{"--joints: entry " + std::to_string(values.size() + 1) + " ('" + item +
                   "') is not a number"};
    }
    if (!std::isfinite(value)) {
      return Error{"--joints: entry " + std::to_string(values.size() + 1) + " is not finite"};
    }
    values.push_back(value);
    if (end == text.size()) break;
    start = end + 1;
  }
  return values;
}

}  // namespace

void RegisterFk(CLI::App& app) {
  auto* command = app.add_subcommand(
      "fk", "Print T_base_sensor of a robot model at one joint configuration (4 x 4, m)");
  struct Options {
    std::string robot;
    std::string joints;
  };
  auto options = std::make_shared<Options>();
  AddInputFile(command, "--robot", options->robot, "Robot model file (YAML)");
  command
      ->add_option("--joints", options->joints,
                   "Joint positions base to tip, comma-separated (rad or m)")
      ->required()
      ->allow_extra_args(false);
  command->callback([options] {
    spdlog::info("fk: robot={} joints={}", options->robot, options->joints);
    const auto file = ReadModelFile(options->robot);
    if (!file) {
      exit_code = Fail(file.error().message);
      return;
    }
    const RobotModel& model = file->model;
    const auto joints = ParseJointList(options->joints);
    if (!joints) {
      exit_code = Fail(joints.error().message);
      return;
    }
    if (joints->size() != model.JointCount()) {
      exit_code = Fail("--joints: " + std::to_string(joints->size()) + " values for the " +
                       std::to_string(model.JointCount()) + " joints of " + options->robot);
      return;
    }
    for (std::size_t i = 0; i < model.JointCount(); ++i) {
      const JointSpec& joint = model.joints[i];
      const double q = (*joints)[i];
      if (q < joint.lower || q > joint.upper) {
        spdlog::warn("joint {} ({}) = {} is outside its limits [{}, {}]", i + 1, joint.name, q,
                     joint.lower, joint.upper);
      }
    }
    Eigen::Matrix4d T_base_sensor = ForwardKinematics(model, *joints).matrix();
    // Entries that print as zero print without a sign ("-0.000000000" reads like an error).
    T_base_sensor = T_base_sensor.unaryExpr([](double v) { return std::abs(v) < 5e-10 ? 0.0 : v; });
    for (int r = 0; r < 4; ++r) {
      std::printf("%16.9f %16.9f %16.9f %16.9f\n", T_base_sensor(r, 0), T_base_sensor(r, 1),
                  T_base_sensor(r, 2), T_base_sensor(r, 3));
    }
  });
}

}  // namespace selfcal::cli
