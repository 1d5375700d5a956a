#include "core/sim/ray_caster.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace selfcal::sim {

struct RayCaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  unsigned triangles_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<float> albedo;  // per triangle; empty: 1
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayCaster::RayCaster(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RayCaster::~RayCaster() = default;

namespace {

std::string DeviceError(RTCDevice device, const std::string& what) {
  const RTCError code = rtcGetDeviceError(device);
  return "embree: " + what + " failed (error " + std::to_string(static_cast<int>(code)) + ")";
}

}  // namespace

Expected<std::unique_ptr<RayCaster>> RayCaster::Create(const Scene& scene) {
  auto impl = std::make_unique<Impl>();
  // One build thread: the BVH (and with it the choice among equally near triangles) is then
  // the same whatever the machine's thread count. Building is fast next to casting.
  impl->device = rtcNewDevice("threads=1");
  if (!impl->device) return Error{DeviceError(nullptr, "creating the device")};
  impl->scene = rtcNewScene(impl->device);
  rtcSetSceneFlags(impl->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl->scene, RTC_BUILD_QUALITY_HIGH);

  if (!scene.mesh.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), scene.mesh.vertices.size()));
    auto* indices = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), scene.mesh.triangles.size()));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geometry);
      return Error{DeviceError(impl->device, "allocating the triangle buffers")};
    }
    for (std::size_t i = 0; i < scene.mesh.vertices.size(); ++i) {
      std::memcpy(vertices + 3 * i, scene.mesh.vertices[i].data(), 3 * sizeof(float));
    }
    for (std::size_t i = 0; i < scene.mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k)
        indices[3 * i + static_cast<std::size_t>(k)] =
            static_cast<unsigned>(scene.mesh.triangles[i][k]);
    }
    rtcCommitGeometry(geometry);
    impl->triangles_id = rtcAttachGeometry(impl->scene, geometry);
    rtcReleaseGeometry(geometry);
    impl->albedo = scene.albedo;
  }
  if (!scene.spheres.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* points = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT4, 4 * sizeof(float),
                                                               scene.spheres.size()));
    if (!points) {
      rtcReleaseGeometry(geometry);
      return Error{DeviceError(impl->device, "allocating the sphere buffer")};
    }
    for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
      const auto& sphere = scene.spheres[i];
      points[4 * i + 0] = static_cast<float>(sphere.center.x());
      points[4 * i + 1] = static_cast<float>(sphere.center.y());
      points[4 * i + 2] = static_cast<float>(sphere.center.z());
      points[4 * i + 3] = static_cast<float>(sphere.radius);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(impl->scene);
  if (rtcGetDeviceError(impl->device) != RTC_ERROR_NONE) {
    return Error{DeviceError(impl->device, "building the scene")};
  }
  return std::unique_ptr<RayCaster>(new RayCaster(std::move(impl)));
}

namespace {

RTCRayHit Query(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double max_distance) {
  RTCRayHit query;
  query.ray.org_x = static_cast<float>(origin.x());
  query.ray.org_y = static_cast<float>(origin.y());
  query.ray.org_z = static_cast<float>(origin.z());
  query.ray.dir_x = static_cast<float>(direction.x());
  query.ray.dir_y = static_cast<float>(direction.y());
  query.ray.dir_z = static_cast<float>(direction.z());
  query.ray.tnear = 0.0f;
  query.ray.tfar = std::isfinite(max_distance) ? static_cast<float>(max_distance)
                                               : std::numeric_limits<float>::infinity();
  query.ray.mask = 0xFFFFFFFFu;
  query.ray.flags = 0;
  query.ray.time = 0.0f;
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return query;
}

}  // namespace

double RayCaster::Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                       double max_distance) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query = Query(origin, direction, max_distance);
  rtcIntersect1(impl_->scene, &context, &query);
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::numeric_limits<double>::infinity();
  return static_cast<double>(query.ray.tfar);
}

RayCaster::Hit RayCaster::CastHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double max_distance) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query = Query(origin, direction, max_distance);
  rtcIntersect1(impl_->scene, &context, &query);
  Hit hit;
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.distance = static_cast<double>(query.ray.tfar);
  const Eigen::Vector3d normal(query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z);
  if (normal.norm() > 0) hit.normal = normal.normalized();
  if (query.hit.geomID == impl_->triangles_id && query.hit.primID < impl_->albedo.size()) {
    hit.albedo = impl_->albedo[query.hit.primID];
  }
  return hit;
}

}  // namespace selfcal::sim
