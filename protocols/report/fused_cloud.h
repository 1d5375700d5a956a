// The scans of a recording fused into one cloud in the base frame with a given model, as the
// paper's Figures 5 and 6 show them: with a good model the scans of one surface lie on each other.
// The report's 3D view and `selfcal export --ply` use it.
#pragma once

#include <cstddef>
#include <vector>

#include "core/calib/dataset.h"
#include "core/model/robot_model.h"
#include "protocols/model_file/ply.h"

namespace selfcal::report {

enum class ScanSelection { kAll, kValidation, kFit };

struct FusedPoint {
  float x = 0, y = 0, z = 0;  // m, base frame
  int scan = 0;               // scan_index of its dataset
};

// Every `stride`-th valid point of the selected datasets, in the base frame of `model`, with
// the stride the smallest that keeps at most `max_points` (0 = all).
std::vector<FusedPoint> FuseScans(const std::vector<calib::Dataset>& datasets,
                                  const RobotModel& model, ScanSelection selection,
                                  std::size_t max_points);

// A colour per scan index, distinct for neighbours (the same in the report and the PLY).
struct Rgb {
  unsigned char red, green, blue;
};
Rgb ScanColour(int scan);

// The points with their scan's colour, for WritePlyFile.
std::vector<PlyPoint> ToPlyPoints(const std::vector<FusedPoint>& points);

}  // namespace selfcal::report
