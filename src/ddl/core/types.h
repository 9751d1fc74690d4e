#pragma once
// Eigen aliases used across modules. Doubles everywhere geometry is estimated; floats only in
// image-sized buffers.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace ddl {

using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;
using Vec4d = Eigen::Vector4d;
using Vec6d = Eigen::Matrix<double, 6, 1>;
using Mat3d = Eigen::Matrix3d;
using Mat4d = Eigen::Matrix4d;
using Mat6d = Eigen::Matrix<double, 6, 6>;
using Quatd = Eigen::Quaterniond;

template <typename T>
using AlignedVector = std::vector<T, Eigen::aligned_allocator<T>>;

}  // namespace ddl
