#include "protocols/report/fused_cloud.h"

#include <array>

#include "core/calib/chain.h"
#include "core/calib/projection.h"
#include "core/model/kinematics.h"

namespace selfcal::report {
namespace {

bool Selected(const calib::Dataset& dataset, ScanSelection selection) {
  switch (selection) {
    case ScanSelection::kAll:
      return true;
    case ScanSelection::kValidation:
      return dataset.validation;
    case ScanSelection::kFit:
      return !dataset.validation;
  }
  return true;
}

}  // namespace

std::vector<FusedPoint> FuseScans(const std::vector<calib::Dataset>& datasets,
                                  const RobotModel& model, ScanSelection selection,
                                  std::size_t max_points) {
  std::size_t valid = 0;
  for (const auto& dataset : datasets) {
    if (Selected(dataset, selection)) valid += dataset.ValidPointCount();
  }
  const std::size_t stride =
      max_points == 0 || valid <= max_points ? 1 : (valid + max_points - 1) / max_points;
  // Raw parameters and scale 1: points in metres (projection.h).
  const calib::Chain chain{JointTypes(model), 1.0, false};
  const std::vector<double> k = ToParameterVector(model);
  std::vector<FusedPoint> fused;
  fused.reserve(valid / stride + datasets.size());
  std::size_t counter = 0;
  for (const auto& dataset : datasets) {
    if (!Selected(dataset, selection)) continue;
    for (const Eigen::Vector3d& p : calib::BasePoints(dataset, chain, k.data())) {
      if (counter++ % stride != 0) continue;
      fused.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()),
                       static_cast<float>(p.z()), dataset.scan_index});
    }
  }
  return fused;
}

Rgb ScanColour(int scan) {
  // Tableau's ten categorical colours: neighbours differ in hue and lightness.
  static constexpr std::array<Rgb, 10> kPalette{{{31, 119, 180},
                                                 {255, 127, 14},
                                                 {44, 160, 44},
                                                 {214, 39, 40},
                                                 {148, 103, 189},
                                                 {140, 86, 75},
                                                 {227, 119, 194},
                                                 {127, 127, 127},
                                                 {188, 189, 34},
                                                 {23, 190, 207}}};
  const int index = scan % static_cast<int>(kPalette.size());
  return kPalette[static_cast<std::size_t>(index < 0 ? -index : index)];
}

std::vector<PlyPoint> ToPlyPoints(const std::vector<FusedPoint>& points) {
  std::vector<PlyPoint> out;
  out.reserve(points.size());
  for (const FusedPoint& p : points) {
    const Rgb colour = ScanColour(p.scan);
    out.push_back({p.x, p.y, p.z, colour.red, colour.green, colour.blue, p.scan});
  }
  return out;
}

}  // namespace selfcal::report
