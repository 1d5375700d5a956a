#include "core/camera/pinhole_intrinsics.h"

#include <cmath>

namespace selfcal {

bool PinholeIntrinsics::IsValid() const {
  return std::isfinite(fx) && std::isfinite(fy) && fx > 0 && fy > 0 && std::isfinite(cx) &&
         std::isfinite(cy);
}

PinholeIntrinsics PinholeIntrinsics::Binned(int factor) const {
  if (factor <= 1) return *this;
  PinholeIntrinsics binned;
  binned.fx = fx / factor;
  binned.fy = fy / factor;
  binned.cx = (cx + 0.5) / factor - 0.5;
  binned.cy = (cy + 0.5) / factor - 0.5;
  return binned;
}

PinholeIntrinsics PinholeIntrinsics::FromFieldOfView(int width, int height, double horizontal_fov,
                                                     double vertical_fov) {
  PinholeIntrinsics k;
  k.fx = width / 2.0 / std::tan(horizontal_fov / 2.0);
  k.fy = height / 2.0 / std::tan(vertical_fov / 2.0);
  k.cx = (width - 1) / 2.0;
  k.cy = (height - 1) / 2.0;
  return k;
}

}  // namespace selfcal
