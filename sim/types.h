#pragma once
/// Basic numeric types of the simulation core.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace fp::sim {

/// Floating-point type of the particle state. Single precision, like the reference CPU library the benchmark
/// compares against; sums that must be exact to round-off (total mass, momentum) are accumulated in double.
using Real = float;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Vec3d = Eigen::Vector3d;
using Quatd = Eigen::Quaterniond;
using Aabb = Eigen::AlignedBox3d;

constexpr double kPi = 3.14159265358979323846;

/// Error raised when the simulation goes unstable (NaN, runaway speed, particle outside the domain). The
/// message names the step and the particle.
class InstabilityError : public std::runtime_error {
 public:
  explicit InstabilityError(const std::string& what) : std::runtime_error(what) {}
};

/// Error raised for invalid input (bad parameter, malformed scene, missing asset). The message is one line.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace fp::sim
