#include "render/camera.h"

#include <algorithm>
#include <cmath>

namespace fp::render {

Mat4 lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up) {
  const Eigen::Vector3f f = (target - eye).normalized();
  const Eigen::Vector3f s = f.cross(up).normalized();
  const Eigen::Vector3f u = s.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4 perspective(float fovY, float aspect, float zNear, float zFar) {
  const float t = 1.0f / std::tan(0.5f * fovY);
  Mat4 m = Mat4::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (zFar + zNear) / (zNear - zFar);
  m(2, 3) = 2.0f * zFar * zNear / (zNear - zFar);
  m(3, 2) = -1.0f;
  return m;
}

Mat4 offAxisPerspective(const FieldOfView& fov, float zNear, float zFar) {
  // the frustum's sides at the near plane
  const float left = zNear * std::tan(fov.angleLeft);
  const float right = zNear * std::tan(fov.angleRight);
  const float down = zNear * std::tan(fov.angleDown);
  const float up = zNear * std::tan(fov.angleUp);
  Mat4 m = Mat4::Zero();
  m(0, 0) = 2.0f * zNear / (right - left);
  m(0, 2) = (right + left) / (right - left);
  m(1, 1) = 2.0f * zNear / (up - down);
  m(1, 2) = (up + down) / (up - down);
  m(2, 2) = (zFar + zNear) / (zNear - zFar);
  m(2, 3) = 2.0f * zFar * zNear / (zNear - zFar);
  m(3, 2) = -1.0f;
  return m;
}

Mat4 viewFromPose(const Eigen::Vector3f& position, const Eigen::Quaternionf& orientation) {
  const Eigen::Matrix3f toEye = orientation.normalized().toRotationMatrix().transpose();
  Mat4 m = Mat4::Identity();
  m.block<3, 3>(0, 0) = toEye;
  m.block<3, 1>(0, 3) = -toEye * position;
  return m;
}

Eigen::Vector3f OrbitCamera::eye() const {
  const Eigen::Vector3f dir(std::cos(pitch) * std::sin(yaw), std::sin(pitch),
                            std::cos(pitch) * std::cos(yaw));
  return target + distance * dir;
}

Mat4 OrbitCamera::view() const {
  return lookAt(eye(), target, Eigen::Vector3f::UnitY());
}

Mat4 OrbitCamera::projection(float aspect) const {
  return perspective(fovY, aspect, std::max(0.01f, 0.05f * distance), 20.0f * distance);
}

void OrbitCamera::frame(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float aspect) {
  target = 0.5f * (lo + hi);
  const float radius = 0.5f * (hi - lo).norm();
  // the bounding sphere fits the narrower of the two fields of view: a distance that surely shows the box
  const float halfFov = 0.5f * std::min(fovY, 2.0f * std::atan(std::tan(0.5f * fovY) * aspect));
  float far = radius / std::sin(halfFov);
  // then move in while every corner stays within 92% of the view (the sphere leaves much of it empty)
  auto fits = [&](float d) {
    distance = d;
    const Mat4 m = projection(aspect) * view();
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3f c(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
      const Eigen::Vector4f q = m * c.homogeneous();
      if (q.w() <= 0.0f || std::abs(q.x()) > 0.92f * q.w() || std::abs(q.y()) > 0.92f * q.w())
        return false;
    }
    return true;
  };
  float near = 0.2f * far;
  for (int it = 0; it < 24; ++it) {
    const float mid = 0.5f * (near + far);
    (fits(mid) ? far : near) = mid;
  }
  distance = far;
}

}  // namespace fp::render
