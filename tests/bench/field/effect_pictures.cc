// field_effect_pictures: what each field effect does to a scan (docs/simulation.md, "Field
// effects"). For every picture of the table below it simulates one scan of a field twin twice,
// once without any effect and once with only that effect (at the twin's magnitude), and writes
// docs/img/effects/NAME.svg: the scan without, the scan with, where and how far its points moved
// in the world as the engine sees them (recorded joint states, true model), and one row of the
// scan as a profile. Built with the project, never run by ctest:
//   build/tests/bench/field/field_effect_pictures [--out docs/img/effects] [NAME...]
// A new effect is one line in kPictures.
#include <yaml-cpp/yaml.h>
#include <zlib.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/calib/joint_interpolation.h"
#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scan_plan.h"
#include "core/sim/simulator.h"
#include "core/util/atomic_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/scenario/effects_file.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"

namespace selfcal::bench {
namespace {

// One picture: the file name, the effect key of the twin (or "latency": only the twin's
// sensor_latency), the field twin in config/scenarios/field/ whose scene, plan and magnitude it
// uses, the first scan to try and how many (the one where the effect changes most is shown),
// and what "without" means: "" = no effect at all, or YAML fields that override the effect's
// (e.g. a box that stays where it stood).
struct PictureSpec {
  const char* name;
  const char* key;
  const char* twin;
  int scan, tries;
  const char* without;
};

constexpr PictureSpec kPictures[] = {
    {"mixed_pixels", "mixed_pixels", "kinect-bunny", 0, 8, ""},
    {"range_bias", "range_bias", "kinect-bunny", 0, 1, ""},
    {"incidence_noise", "incidence_noise", "kinect-office", 0, 8, ""},
    {"grazing_dropout", "grazing_dropout", "kinect-office", 0, 8, ""},
    {"baseline_shadows", "baseline_shadows", "photoneo-bunny", 0, 4, ""},
    {"baseline_shadows-wenglor", "baseline_shadows", "wenglor-bunny", 0, 4, ""},
    {"intrinsics", "intrinsics", "kinect-bunny", 0, 1, ""},
    {"joint_elasticity", "joint_elasticity", "kinect-office", 0, 8, ""},
    {"timing", "timing", "hokuyo-office", 1, 1, ""},
    {"latency", "latency", "hokuyo-office", 1, 1, ""},
    {"self_view", "self_view", "hokuyo-office", 1, 1, ""},
    {"walker", "walker", "hokuyo-office", 5, 1, ""},
    {"moved_object", "moved_object", "kinect-office", 14, 21, "{after_scan: 1000}"},
    {"multipath", "multipath", "kinect-bunny", 0, 8, ""},
    {"dark_dropout", "dark_dropout", "kinect-office", 0, 8, ""},
    {"dark_dropout-hokuyo", "dark_dropout", "hokuyo-office", 1, 1, ""},
    {"speckle", "speckle", "wenglor-bunny", 0, 1, ""},
    {"thermal_growth", "thermal_growth", "hokuyo-office", 27, 1, ""},
    {"backlash", "backlash", "hokuyo-office", 1, 1, ""},
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Fmt(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// ---- Scenarios ------------------------------------------------------------------------------

// The twin with only `key` on ("" = nothing on; "latency" = only its sensor_latency), its fields
// overridden by the YAML map `overrides` ("" = none).
Expected<Scenario> VariantOf(const std::string& twin_path, const std::string& key,
                             const std::string& overrides = "") {
  YAML::Node twin;
  try {
    twin = YAML::LoadFile(twin_path);
  } catch (const YAML::Exception& e) {
    return Error{twin_path + ": " + e.what()};
  }
  const YAML::Node effects = twin["effects"];
  YAML::Node variant = YAML::Clone(twin);
  variant.remove("effects");
  if (key != "latency") variant["sensor_latency"] = 0.0;
  if (!key.empty() && key != "latency") {
    if (!effects || !effects[key]) return Error{twin_path + ": no effect '" + key + "'"};
    YAML::Node effect = YAML::Clone(effects[key]);
    if (!overrides.empty()) {
      for (const auto& field : YAML::Load(overrides)) {
        effect[field.first.as<std::string>()] = field.second;
      }
    }
    variant["effects"][key] = effect;
  }
  YAML::Emitter out;
  out << variant;
  return ParseScenario(out.c_str(), twin_path,
                       std::filesystem::path(twin_path).parent_path().string());
}

// ---- One scan as a grid -----------------------------------------------------------------------

// A scan in the sensor's own layout: camera rows x columns, or frames (LiDAR rotations, line
// profiles) x cells. `measure` is what the sensor reports (range or depth z, NaN = none),
// `world` the point where the engine puts it: recorded joint states interpolated at the
// message stamp (latency 0), the true model.
struct ScanGrid {
  SensorLayout kind = SensorLayout::kDepthCamera;
  int width = 0, rows = 0;
  std::vector<double> measure;
  std::vector<Eigen::Vector3d> world;
};

calib::JointStateSeries SeriesOf(const sim::SimSegment& segment) {
  calib::JointStateSeries series;
  series.joint_count = segment.joint_states.front().positions.size();
  for (const auto& state : segment.joint_states) {
    series.utime.push_back(state.stamp_us);
    series.positions.insert(series.positions.end(), state.positions.begin(), state.positions.end());
  }
  return series;
}

Expected<ScanGrid> GridOf(const sim::SimSegment& segment, const sim::SensorModel& sensor,
                          const RobotModel& truth) {
  ScanGrid grid;
  grid.kind = sensor.kind;
  const bool camera = sensor.kind == SensorLayout::kDepthCamera;
  const auto& frames = segment.frames;
  if (frames.empty()) return Error{"the scan has no sensor frames"};
  // A camera scan: its middle frame; a sweep: every frame.
  const std::size_t first = camera ? frames.size() / 2 : 0;
  const std::size_t last = camera ? first + 1 : frames.size();
  grid.width = sensor.width;
  grid.rows = camera ? sensor.height : static_cast<int>(last - first);
  const auto rays = sensor.Rays();
  const calib::JointStateSeries series = SeriesOf(segment);
  std::vector<double> q(series.joint_count);
  for (std::size_t f = first; f < last; ++f) {
    const auto& frame = frames[f];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int i = 0; i < sensor.CellCount(); ++i) {
      const bool lidar = sensor.kind == SensorLayout::kRotatingLidar;
      const double t =
          static_cast<double>(frame.stamp_us) + (lidar ? i * sensor.time_per_ray * 1e6 : 0);
      if (i == 0 || lidar) {
        if (auto s = calib::InterpolateJoints(series, t, 1e6, q); !s) return s.error();
        pose = ForwardKinematics(truth, q);
      }
      Eigen::Vector3d p;
      double m;
      if (lidar) {
        m = frame.ranges[static_cast<std::size_t>(i)];
        p = m * rays[static_cast<std::size_t>(i)];
      } else {
        p = frame.points[static_cast<std::size_t>(i)].cast<double>();
        m = p.z();
      }
      grid.measure.push_back(std::isnan(m) ? kNaN : m);
      grid.world.push_back(std::isnan(m) ? Eigen::Vector3d::Constant(kNaN)
                                         : Eigen::Vector3d(pose * p));
    }
  }
  return grid;
}

struct Simulated {
  ScanGrid grid;
  sim::SensorModel sensor;
};

// The scans `scans` of a scenario (its own plan, its own truth: the same for every variant).
Expected<std::vector<Simulated>> SimulateScans(Scenario scenario, const std::vector<int>& scans) {
  auto setup = PrepareSimulation(std::move(scenario));
  if (!setup) return setup.error();
  auto caster = sim::RayCaster::Create(setup->scene);
  if (!caster) return caster.error();
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  if (!plan) return plan.error();
  const sim::Simulator simulator(setup->truth, setup->sensor, **caster, *plan,
                                 setup->scenario.recording);
  std::vector<Simulated> out;
  for (int k : scans) {
    if (k >= simulator.SegmentCount()) return Error{"no scan " + std::to_string(k)};
    auto grid = GridOf(simulator.Segment(k), setup->sensor, setup->truth);
    if (!grid) return Error{"scan " + std::to_string(k) + ": " + grid.error().message};
    out.push_back({std::move(*grid), setup->sensor});
  }
  return out;
}

// ---- What changed ---------------------------------------------------------------------------

enum class Change : std::uint8_t { kNone, kMoved, kLost, kNew, kEmpty };

struct Comparison {
  std::vector<Change> change;
  std::vector<double> moved;  // |world with - world without| [m], NaN unless both returned
  std::size_t cells = 0, valid = 0, moved_count = 0, lost = 0, added = 0;
  double median_mm = 0, p99_mm = 0, max_mm = 0;
};

Comparison Compare(const ScanGrid& without, const ScanGrid& with) {
  Comparison c;
  c.cells = without.measure.size();
  std::vector<double> distances;
  for (std::size_t i = 0; i < c.cells; ++i) {
    const bool a = !std::isnan(without.measure[i]), b = !std::isnan(with.measure[i]);
    double d = kNaN;
    Change change = Change::kEmpty;
    if (a && b) {
      d = (with.world[i] - without.world[i]).norm();
      change = d > 1e-7 ? Change::kMoved : Change::kNone;
      if (d > 1e-7) distances.push_back(d * 1e3);
    } else if (a) {
      change = Change::kLost;
    } else if (b) {
      change = Change::kNew;
    }
    c.valid += a ? 1 : 0;
    c.moved_count += change == Change::kMoved ? 1 : 0;
    c.lost += change == Change::kLost ? 1 : 0;
    c.added += change == Change::kNew ? 1 : 0;
    c.change.push_back(change);
    c.moved.push_back(d);
  }
  if (!distances.empty()) {
    std::sort(distances.begin(), distances.end());
    const auto at = [&](double f) {
      return distances[static_cast<std::size_t>(f * static_cast<double>(distances.size() - 1))];
    };
    c.median_mm = at(0.5);
    c.p99_mm = at(0.99);
    c.max_mm = distances.back();
  }
  return c;
}

// A score for choosing the scan that shows an effect best: cells lost or added count fully,
// moved cells by their displacement up to 1 cm.
double Score(const Comparison& c) {
  double score = static_cast<double>(c.lost + c.added);
  for (double d : c.moved) {
    if (!std::isnan(d)) score += std::min(d, 0.01) / 0.01;
  }
  return score;
}

// ---- PNG (8-bit palette), base64 ------------------------------------------------------------

using Rgb = std::array<std::uint8_t, 3>;

void PutChunk(std::string& png, const char* type, const std::string& data) {
  const auto be32 = [&](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) png.push_back(static_cast<char>((v >> s) & 0xff));
  };
  be32(static_cast<std::uint32_t>(data.size()));
  const std::string body = std::string(type, 4) + data;
  png += body;
  be32(static_cast<std::uint32_t>(
      crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
}

// `pixels` are palette indices, row-major.
std::string EncodePng(int width, int height, const std::vector<std::uint8_t>& pixels,
                      const std::vector<Rgb>& palette) {
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string header;
  for (std::uint32_t v : {static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height)}) {
    for (int s = 24; s >= 0; s -= 8) header.push_back(static_cast<char>((v >> s) & 0xff));
  }
  header += std::string("\x08\x03\x00\x00\x00", 5);  // 8 bit, palette, deflate, no interlace
  PutChunk(png, "IHDR", header);
  std::string colours;
  for (const Rgb& c : palette) colours.append(reinterpret_cast<const char*>(c.data()), 3);
  PutChunk(png, "PLTE", colours);
  std::string raw;
  for (int y = 0; y < height; ++y) {
    raw.push_back('\0');  // no filter
    raw.append(
        reinterpret_cast<const char*>(pixels.data()) + static_cast<std::ptrdiff_t>(y) * width,
        static_cast<std::size_t>(width));
  }
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(size, '\0');
  compress2(reinterpret_cast<Bytef*>(packed.data()), &size,
            reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), 9);
  packed.resize(size);
  PutChunk(png, "IDAT", packed);
  PutChunk(png, "IEND", "");
  return png;
}

std::string Base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<std::uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size())
      v |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<std::uint8_t>(bytes[i + 2]);
    out.push_back(table[(v >> 18) & 63]);
    out.push_back(table[(v >> 12) & 63]);
    out.push_back(i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=');
    out.push_back(i + 2 < bytes.size() ? table[v & 63] : '=');
  }
  return out;
}

// ---- Colours ----------------------------------------------------------------------------------

Rgb Ramp(const std::vector<Rgb>& stops, double f) {
  f = std::clamp(f, 0.0, 1.0) * static_cast<double>(stops.size() - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(f), stops.size() - 2);
  const double w = f - static_cast<double>(i);
  Rgb c;
  for (int k = 0; k < 3; ++k) {
    c[static_cast<std::size_t>(k)] =
        static_cast<std::uint8_t>(std::lround((1 - w) * stops[i][static_cast<std::size_t>(k)] +
                                              w * stops[i + 1][static_cast<std::size_t>(k)]));
  }
  return c;
}

const std::vector<Rgb> kViridis = {{68, 1, 84},    {71, 45, 123},  {59, 82, 139},
                                   {44, 114, 142}, {33, 145, 140}, {40, 174, 128},
                                   {94, 201, 98},  {173, 220, 48}, {253, 231, 37}};
const std::vector<Rgb> kHeat = {
    {255, 255, 255}, {253, 212, 158}, {252, 141, 89}, {215, 48, 31}, {127, 0, 0}};
constexpr int kLevels = 240;  // palette entries of a ramp; then the special colours
constexpr std::uint8_t kBlank = kLevels, kLostIndex = kLevels + 1, kNewIndex = kLevels + 2;
const Rgb kBlankColour = {217, 217, 217}, kLostColour = {0, 0, 0}, kNewColour = {33, 102, 255};

std::string Hex(const Rgb& c) {
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buffer;
}

std::vector<Rgb> Palette(const std::vector<Rgb>& stops) {
  std::vector<Rgb> palette;
  for (int i = 0; i < kLevels; ++i) palette.push_back(Ramp(stops, i / double(kLevels - 1)));
  palette.push_back(kBlankColour);
  palette.push_back(kLostColour);
  palette.push_back(kNewColour);
  return palette;
}

std::uint8_t Level(double f) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(f, 0.0, 1.0) * (kLevels - 1)));
}

// 1, 2 or 5 times a power of ten, at least `value`.
double NiceCeil(double value) {
  const double p = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= value * (1 - 1e-9)) return m * p;
  }
  return 10 * p;
}

// ---- SVG ------------------------------------------------------------------------------------

// Display grid: at most kMaxColumns x kMaxRows cells, every `step` one (for the change panel the
// cell of the block that changed most, so that single flying pixels stay visible).
constexpr int kMaxColumns = 380, kMaxRows = 300;

struct Layout {
  int step_u = 1, step_v = 1, columns = 0, rows = 0;
  double scale = 1;  // SVG px per display cell
};

Layout LayoutOf(const ScanGrid& g) {
  Layout l;
  l.step_u = (g.width + kMaxColumns - 1) / kMaxColumns;
  l.step_v = (g.rows + kMaxRows - 1) / kMaxRows;
  l.columns = (g.width + l.step_u - 1) / l.step_u;
  l.rows = (g.rows + l.step_v - 1) / l.step_v;
  l.scale = std::min(300.0 / l.columns, 260.0 / l.rows);
  return l;
}

std::vector<std::uint8_t> MeasurePixels(const ScanGrid& g, const Layout& l, double lo, double hi) {
  std::vector<std::uint8_t> pixels;
  for (int r = 0; r < l.rows; ++r) {
    for (int c = 0; c < l.columns; ++c) {
      const double m = g.measure[static_cast<std::size_t>(r * l.step_v * g.width + c * l.step_u)];
      pixels.push_back(std::isnan(m) ? kBlank : Level((m - lo) / (hi - lo)));
    }
  }
  return pixels;
}

std::vector<std::uint8_t> ChangePixels(const ScanGrid& g, const Comparison& cmp, const Layout& l,
                                       double scale_m) {
  std::vector<std::uint8_t> pixels;
  for (int r = 0; r < l.rows; ++r) {
    for (int c = 0; c < l.columns; ++c) {
      // The most telling cell of the block: lost, then new, then the largest move.
      int rank = -1;
      std::uint8_t pixel = kBlank;
      for (int v = r * l.step_v; v < std::min(g.rows, (r + 1) * l.step_v); ++v) {
        for (int u = c * l.step_u; u < std::min(g.width, (c + 1) * l.step_u); ++u) {
          const std::size_t i = static_cast<std::size_t>(v * g.width + u);
          const Change ch = cmp.change[i];
          const double d = cmp.moved[i];
          const int this_rank = ch == Change::kLost    ? 3
                                : ch == Change::kNew   ? 2
                                : ch == Change::kEmpty ? -1
                                                       : 0;
          if (this_rank > rank ||
              (this_rank == 0 && rank == 0 && d > 0 && Level(d / scale_m) > pixel)) {
            rank = this_rank;
            pixel = ch == Change::kLost  ? kLostIndex
                    : ch == Change::kNew ? kNewIndex
                                         : Level(d / scale_m);
          }
        }
      }
      pixels.push_back(pixel);
    }
  }
  return pixels;
}

std::string Text(double x, double y, const std::string& s, const char* extra = "") {
  std::ostringstream o;
  o << "<text x=\"" << x << "\" y=\"" << y << "\" " << extra << ">" << s << "</text>\n";
  return o.str();
}

std::string Line(double x1, double y1, double x2, double y2, const char* style) {
  std::ostringstream o;
  o << "<line x1=\"" << x1 << "\" y1=\"" << y1 << "\" x2=\"" << x2 << "\" y2=\"" << y2 << "\" "
    << style << "/>\n";
  return o.str();
}

// Ticks on an axis of `cells` cells drawn over `length` px: about five nice steps.
std::vector<int> Ticks(int cells) {
  const int step = static_cast<int>(NiceCeil(cells / 5.0));
  std::vector<int> ticks;
  for (int t = 0; t < cells; t += step) ticks.push_back(t);
  return ticks;
}

struct AxisNames {
  std::string u, v, measure, row;
};

AxisNames NamesOf(SensorLayout kind) {
  switch (kind) {
    case SensorLayout::kRotatingLidar:
      return {"ray in the rotation", "rotation in the sweep", "range [m]", "rotation"};
    case SensorLayout::kLineScanner:
      return {"point in the profile", "profile in the sweep", "depth z [m]", "profile"};
    case SensorLayout::kDepthCamera:
      break;
  }
  return {"column u [px]", "row v [px]", "depth z [m]", "row"};
}

// An image panel at (x, y) with its axes; `row` (-1: none) is marked with a dashed line.
std::string ImagePanel(double x, double y, const Layout& l, const ScanGrid& g,
                       const std::string& png, const std::string& title, int row) {
  const AxisNames names = NamesOf(g.kind);
  const double w = l.columns * l.scale, h = l.rows * l.scale;
  std::ostringstream o;
  o << Text(x, y - 8, title, "font-weight=\"bold\"");
  o << "<image x=\"" << x << "\" y=\"" << y << "\" width=\"" << w << "\" height=\"" << h
    << "\" preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\" "
       "href=\"data:image/png;base64,"
    << Base64(png) << "\"/>\n";
  o << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << w << "\" height=\"" << h
    << "\" fill=\"none\" stroke=\"#333\"/>\n";
  for (int t : Ticks(g.width)) {
    const double tx = x + t * w / g.width;
    o << Line(tx, y + h, tx, y + h + 4, "stroke=\"#333\"")
      << Text(tx, y + h + 15, std::to_string(t), "text-anchor=\"middle\"");
  }
  for (int t : Ticks(g.rows)) {
    const double ty = y + t * h / g.rows;
    o << Line(x - 4, ty, x, ty, "stroke=\"#333\"")
      << Text(x - 6, ty + 4, std::to_string(t), "text-anchor=\"end\"");
  }
  o << Text(x + w / 2, y + h + 30, names.u, "text-anchor=\"middle\"");
  o << "<text transform=\"translate(" << x - 36 << "," << y + h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << names.v << "</text>\n";
  if (row >= 0) {
    const double ry = y + (row + 0.5) * h / g.rows;
    o << Line(x, ry, x + w, ry, "stroke=\"#e7298a\" stroke-dasharray=\"4 3\" stroke-width=\"1.2\"");
  }
  return o.str();
}

std::string ColourBar(double x, double y, double w, const std::vector<Rgb>& stops, double lo,
                      double hi, const std::string& label, const char* format) {
  std::ostringstream o;
  const int n = 48;
  for (int i = 0; i < n; ++i) {
    o << "<rect x=\"" << x + i * w / n << "\" y=\"" << y << "\" width=\"" << w / n + 0.5
      << "\" height=\"8\" fill=\"" << Hex(Ramp(stops, (i + 0.5) / n)) << "\"/>\n";
  }
  o << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << w
    << "\" height=\"8\" fill=\"none\" stroke=\"#333\"/>\n";
  for (int i = 0; i <= 4; ++i) {
    const double tx = x + i * w / 4;
    o << Line(tx, y + 8, tx, y + 11, "stroke=\"#333\"")
      << Text(tx, y + 22, Fmt(format, lo + (hi - lo) * i / 4), "text-anchor=\"middle\"");
  }
  o << Text(x + w / 2, y + 36, label, "text-anchor=\"middle\"");
  return o.str();
}

std::string Swatch(double x, double y, const Rgb& colour, const std::string& label) {
  std::ostringstream o;
  o << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"10\" height=\"10\" fill=\"" << Hex(colour)
    << "\" stroke=\"#333\"/>\n"
    << Text(x + 14, y + 9, label);
  return o.str();
}

// A plot of one row at (x, y), w x h: `series` of (cell, value) points, NaN skipped.
struct Series {
  std::vector<double> values;
  std::string colour;
  double radius;
};

std::string RowPlot(double x, double y, double w, double h, int cells,
                    const std::vector<Series>& series, const std::string& y_label,
                    const std::string& x_label, bool symmetric) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series) {
    for (double v : s.values) {
      if (!std::isnan(v) && std::abs(v) < 1e11) lo = std::min(lo, v), hi = std::max(hi, v);
    }
  }
  if (!(lo <= hi)) lo = -1, hi = 1;
  if (symmetric) {
    // The 98th percentile of |value|: a few outliers (flying pixels, edges) are clipped at the
    // border instead of flattening what most cells show.
    std::vector<double> magnitudes;
    for (const auto& s : series) {
      for (double v : s.values) {
        if (!std::isnan(v) && std::abs(v) < 1e11) magnitudes.push_back(std::abs(v));
      }
    }
    std::sort(magnitudes.begin(), magnitudes.end());
    const double p98 = magnitudes.empty() ? 1.0
                                          : magnitudes[static_cast<std::size_t>(
                                                0.98 * static_cast<double>(magnitudes.size() - 1))];
    hi = NiceCeil(std::max(p98, 1e-3)), lo = -hi;
  }
  if (hi - lo < 1e-9) lo -= 0.5, hi += 0.5;
  const double pad = symmetric ? 0 : 0.05 * (hi - lo);
  lo -= pad, hi += pad;
  std::ostringstream o;
  o << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << w << "\" height=\"" << h
    << "\" fill=\"none\" stroke=\"#333\"/>\n";
  const auto py = [&](double v) { return y + h - (v - lo) / (hi - lo) * h; };
  for (int i = 0; i <= 4; ++i) {
    const double v = lo + (hi - lo) * i / 4;
    o << Line(x - 4, py(v), x, py(v), "stroke=\"#333\"")
      << Text(x - 6, py(v) + 4,
              Fmt(hi - lo < 0.05 ? "%.4f"
                  : hi - lo < 5  ? "%.3g"
                                 : "%.0f",
                  v),
              "text-anchor=\"end\"");
  }
  if (symmetric) o << Line(x, py(0), x + w, py(0), "stroke=\"#999\" stroke-dasharray=\"2 2\"");
  for (int t : Ticks(cells)) {
    const double tx = x + t * w / cells;
    o << Line(tx, y + h, tx, y + h + 4, "stroke=\"#333\"");
    if (!x_label.empty()) o << Text(tx, y + h + 15, std::to_string(t), "text-anchor=\"middle\"");
  }
  if (!x_label.empty()) o << Text(x + w / 2, y + h + 30, x_label, "text-anchor=\"middle\"");
  o << "<text transform=\"translate(" << x - 50 << "," << y + h / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << y_label << "</text>\n";
  for (const auto& s : series) {
    // Round dots: zero-length segments with round caps, one path per series.
    o << "<path stroke=\"" << s.colour << "\" stroke-width=\"" << 2 * s.radius
      << "\" stroke-linecap=\"round\" fill=\"none\" d=\"";
    for (int i = 0; i < cells; ++i) {
      const double v = s.values[static_cast<std::size_t>(i)];
      if (std::isnan(v)) continue;
      o << "M" << Fmt("%.1f", x + (i + 0.5) * w / cells) << " "
        << Fmt("%.1f", std::clamp(py(v), y, y + h)) << "h0";
    }
    o << "\"/>\n";
  }
  return o.str();
}

// The row of the scan where the effect shows most (of rows within 10 % of that, the one nearest
// the middle).
int BestRow(const ScanGrid& g, const Comparison& c) {
  std::vector<double> scores;
  for (int r = 0; r < g.rows; ++r) {
    double score = 0;
    for (int u = 0; u < g.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(r * g.width + u);
      score += c.change[i] == Change::kLost || c.change[i] == Change::kNew ? 1.0
               : std::isnan(c.moved[i])                                    ? 0.0
                                        : std::min(c.moved[i], 0.01) / 0.01;
    }
    scores.push_back(score);
  }
  const double top = *std::max_element(scores.begin(), scores.end());
  int best = 0;
  for (int r = 0; r < g.rows; ++r) {
    if (scores[static_cast<std::size_t>(r)] >= 0.9 * top &&
        std::abs(r - g.rows / 2) < std::abs(best - g.rows / 2)) {
      best = r;
    }
  }
  return scores[static_cast<std::size_t>(best)] >= 0.9 * top ? best : 0;
}

struct Caption {
  std::string title, setup, effect, without = "without the effect";
};

std::string Figure(const Caption& caption, const ScanGrid& without, const ScanGrid& with,
                   const Comparison& cmp) {
  const Layout l = LayoutOf(without);
  std::vector<double> valid;
  for (const ScanGrid* g : {&without, &with}) {
    for (double m : g->measure) {
      if (!std::isnan(m)) valid.push_back(m);
    }
  }
  std::sort(valid.begin(), valid.end());
  double lo = valid.empty() ? 0 : valid[valid.size() / 100];
  double hi = valid.empty() ? 1 : valid[valid.size() - 1 - valid.size() / 100];
  if (hi - lo < 1e-6) hi = lo + 1e-3;
  const double scale_mm = NiceCeil(std::max(cmp.p99_mm, 0.01));
  const std::vector<Rgb> viridis = Palette(kViridis), heat = Palette(kHeat);
  const int row = BestRow(without, cmp);

  const double panel_w = l.columns * l.scale, panel_h = l.rows * l.scale;
  const double x0 = 60, gap = 80, y0 = 118;
  const double width = x0 + 3 * panel_w + 2 * gap + 30;
  const double plot_y = y0 + panel_h + 110, plot_h = 110;
  const double height = plot_y + 2 * plot_h + 70;
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << " " << height
    << "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"11\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << Text(x0 - 40, 24, caption.title, "font-size=\"15\" font-weight=\"bold\"");
  o << Text(x0 - 40, 44, caption.setup);
  o << Text(x0 - 40, 62, caption.effect, "font-family=\"DejaVu Sans Mono, monospace\"");
  std::ostringstream stats;
  stats << "cells " << cmp.cells << ", returned without " << cmp.valid
        << "; with: " << cmp.moved_count << " moved (median " << Fmt("%.3g", cmp.median_mm)
        << " mm, 99 % " << Fmt("%.3g", cmp.p99_mm) << " mm, max " << Fmt("%.3g", cmp.max_mm)
        << " mm), " << cmp.lost << " lost, " << cmp.added << " new";
  o << Text(x0 - 40, 80, stats.str());

  const double x1 = x0 + panel_w + gap, x2 = x1 + panel_w + gap;
  o << ImagePanel(x0, y0, l, without,
                  EncodePng(l.columns, l.rows, MeasurePixels(without, l, lo, hi), viridis),
                  caption.without, row);
  o << ImagePanel(x1, y0, l, with,
                  EncodePng(l.columns, l.rows, MeasurePixels(with, l, lo, hi), viridis),
                  "with the effect", row);
  o << ImagePanel(x2, y0, l, with,
                  EncodePng(l.columns, l.rows, ChangePixels(with, cmp, l, scale_mm * 1e-3), heat),
                  "where the points moved (world)", row);
  const AxisNames names = NamesOf(without.kind);
  const double bar_y = y0 + panel_h + 44;
  o << ColourBar(x0 + panel_w * 0.1, bar_y, panel_w * 0.8, kViridis, lo, hi, names.measure,
                 hi - lo < 0.5 ? "%.3f" : "%.2f");
  o << ColourBar(x1 + panel_w * 0.1, bar_y, panel_w * 0.8, kViridis, lo, hi, names.measure,
                 hi - lo < 0.5 ? "%.3f" : "%.2f");
  o << ColourBar(x2, bar_y, panel_w * 0.55, kHeat, 0, scale_mm, "|moved| [mm] (clipped)",
                 scale_mm < 0.1  ? "%.3f"
                 : scale_mm < 1  ? "%.2f"
                 : scale_mm < 10 ? "%.3g"
                                 : "%.0f");
  o << Swatch(x2 + panel_w * 0.66, bar_y - 2, kLostColour, "lost");
  o << Swatch(x2 + panel_w * 0.66, bar_y + 12, kNewColour, "new");
  o << Swatch(x2 + panel_w * 0.66, bar_y + 26, kBlankColour, "none");

  // The marked row as profiles: the measure, then what changed.
  const std::size_t begin = static_cast<std::size_t>(row * without.width);
  const auto row_of = [&](const std::vector<double>& v) {
    return std::vector<double>(
        v.begin() + static_cast<std::ptrdiff_t>(begin),
        v.begin() + static_cast<std::ptrdiff_t>(begin + static_cast<std::size_t>(without.width)));
  };
  std::vector<double> delta(static_cast<std::size_t>(without.width)), moved = row_of(cmp.moved);
  std::vector<double> lost(delta.size(), kNaN), added(delta.size(), kNaN);
  for (std::size_t i = 0; i < delta.size(); ++i) {
    delta[i] = (with.measure[begin + i] - without.measure[begin + i]) * 1e3;
    moved[i] *= 1e3;
    // Drawn clipped at the bottom (lost) and top (new) border.
    if (cmp.change[begin + i] == Change::kLost) lost[i] = -1e12;
    if (cmp.change[begin + i] == Change::kNew) added[i] = 1e12;
  }
  const double plot_w = width - x0 - 60;
  o << Text(x0, plot_y - 10, "the dashed line: " + names.row + " " + std::to_string(row),
            "font-weight=\"bold\"");
  o << RowPlot(x0, plot_y, plot_w, plot_h, without.width,
               {{row_of(without.measure), "#888", 1.6}, {row_of(with.measure), "#d7301f", 1.0}},
               names.measure, "", false);
  o << Swatch(x0 + plot_w - 160, plot_y - 20, {136, 136, 136}, "without");
  o << Swatch(x0 + plot_w - 80, plot_y - 20, {215, 48, 31}, "with");
  const double plot2_y = plot_y + plot_h + 26;
  o << RowPlot(x0, plot2_y, plot_w, plot_h, without.width,
               {{moved, "#fc8d59", 1.2},
                {delta, "#2166ff", 1.0},
                {lost, "#000", 1.4},
                {added, Hex(kNewColour), 1.4}},
               "with - without [mm]", names.u, true);
  o << Swatch(x0 + plot_w - 560, plot2_y - 20, kLostColour, "lost (bottom), new (top)");
  o << Swatch(x0 + plot_w - 370, plot2_y - 20, {33, 102, 255},
              "the measure (" + names.measure.substr(0, names.measure.find(" [")) + ")");
  o << Swatch(x0 + plot_w - 150, plot2_y - 20, {252, 141, 89}, "|moved| in the world");
  o << "</svg>\n";
  return o.str();
}

// ---- One picture ------------------------------------------------------------------------------

// Numbers of a formatted YAML text with 6 significant digits (0.0030000000000000001 -> 0.003).
std::string ShortNumbers(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    const bool starts = std::isdigit(static_cast<unsigned char>(text[i])) ||
                        (text[i] == '-' && i + 1 < text.size() &&
                         std::isdigit(static_cast<unsigned char>(text[i + 1])));
    if (!starts ||
        (i > 0 && (std::isalnum(static_cast<unsigned char>(text[i - 1])) || text[i - 1] == '_'))) {
      out.push_back(text[i++]);
      continue;
    }
    std::size_t used = 0;
    const double value = std::stod(text.substr(i), &used);
    out += Fmt("%.6g", value);
    i += used;
  }
  return out;
}

std::string EffectText(const Scenario& s, const std::string& key) {
  if (key == "latency") {
    return "sensor_latency: " + Fmt("%g", s.recording.latency) + " s (the engine is run with 0)";
  }
  std::string text = FormatEffects(s.recording.effects);
  // One line: "effects:\n  key: {...}" -> "key: {...}".
  text.erase(0, text.find('\n') + 1);
  text.erase(std::remove(text.begin(), text.end(), '\n'), text.end());
  text.erase(0, text.find_first_not_of(' '));
  return ShortNumbers(text);
}

int MakePicture(const PictureSpec& spec, const std::filesystem::path& field_dir,
                const std::filesystem::path& out_dir) {
  const std::string twin_path = (field_dir / (std::string(spec.twin) + ".yaml")).string();
  const bool baseline_is_off = std::string(spec.without).empty();
  auto without_scenario =
      baseline_is_off ? VariantOf(twin_path, "") : VariantOf(twin_path, spec.key, spec.without);
  auto with_scenario = VariantOf(twin_path, spec.key);
  if (!without_scenario || !with_scenario) {
    std::cerr << "error: " << (without_scenario ? with_scenario : without_scenario).error().message
              << "\n";
    return 1;
  }
  std::vector<int> scans;
  for (int k = spec.scan; k < spec.scan + spec.tries; ++k) scans.push_back(k);
  auto without = SimulateScans(*without_scenario, scans);
  auto with = SimulateScans(*with_scenario, scans);
  if (!without || !with) {
    std::cerr << "error: " << spec.name << ": "
              << (without ? with.error() : without.error()).message << "\n";
    return 1;
  }
  std::size_t best = 0;
  double best_score = -1;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const double score = Score(Compare((*without)[i].grid, (*with)[i].grid));
    if (score > best_score) best_score = score, best = i;
  }
  const ScanGrid& a = (*without)[best].grid;
  const ScanGrid& b = (*with)[best].grid;
  const Comparison cmp = Compare(a, b);
  Caption caption;
  caption.title = std::string(spec.key) + ": what it does to a scan";
  caption.setup =
      "field twin " + std::string(spec.twin) + " (" + kSensorLayoutNames.Name(a.kind) + "), seed " +
      std::to_string(with_scenario->seed) + ", scan " + std::to_string(scans[best]) +
      (a.kind == SensorLayout::kDepthCamera ? " (its frame)" : " (every frame of the sweep)") +
      (baseline_is_off ? ", simulated without any effect and with only this one"
                       : ", simulated with this one as below and with " +
                             std::string(spec.without) + " (\"without\")") +
      "; world = recorded joint states, true model";
  caption.effect = EffectText(*with_scenario, spec.key);
  if (!baseline_is_off) caption.without = "with " + std::string(spec.without);
  const std::filesystem::path out = out_dir / (std::string(spec.name) + ".svg");
  if (auto s = WriteFileAtomically(out.string(), Figure(caption, a, b, cmp)); !s) {
    std::cerr << "error: " << s.error().message << "\n";
    return 1;
  }
  std::cout << out.string() << ": scan " << scans[best] << ", " << cmp.moved_count << " moved (max "
            << Fmt("%.3g", cmp.max_mm) << " mm), " << cmp.lost << " lost, " << cmp.added
            << " new of " << cmp.cells << "\n";
  return 0;
}

}  // namespace
}  // namespace selfcal::bench

int main(int argc, char** argv) {
  using selfcal::bench::kPictures;
  std::filesystem::path out =
      std::filesystem::path(SELFCAL_SOURCE_DIR) / "docs" / "img" / "effects";
  const std::filesystem::path field_dir =
      std::filesystem::path(SELFCAL_SOURCE_DIR) / "config" / "scenarios" / "field";
  std::vector<std::string> names;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (arg == "--list") {
      for (const auto& p : kPictures) std::cout << p.name << " " << p.key << " " << p.twin << "\n";
      return 0;
    } else if (arg.starts_with("-")) {
      std::cerr << "usage: field_effect_pictures [--out DIR] [--list] [NAME...]\n";
      return 2;
    } else {
      names.push_back(arg);
    }
  }
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (error) {
    std::cerr << "error: " << out.string() << ": " << error.message() << "\n";
    return 1;
  }
  int failures = 0, made = 0;
  for (const auto& spec : kPictures) {
    if (!names.empty() && std::find(names.begin(), names.end(), spec.name) == names.end()) continue;
    failures += selfcal::bench::MakePicture(spec, field_dir, out);
    ++made;
  }
  if (made == 0) {
    std::cerr << "error: no picture of that name (--list)\n";
    return 2;
  }
  return failures == 0 ? 0 : 1;
}
