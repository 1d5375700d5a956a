// The paper's "Data Structure": a sensor gives one point (rotating LiDAR), one line (line
// scanner) or one image (depth camera) per timestamp. Sensor files, the simulator and the
// recording assembly all speak of this one type.
#pragma once

namespace selfcal {

enum class SensorLayout { kRotatingLidar, kLineScanner, kDepthCamera };

}  // namespace selfcal
