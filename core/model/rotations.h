// Elementary rotations of docs/method.md, templated on the scalar so that Ceres
// Jets pass through them.
//
//   Rx(a) = [[1,0,0],[0,c,-s],[0,s,c]]
//   Ry(a) = [[c,0,s],[0,1,0],[-s,0,c]]
//   Rz(a) = [[c,-s,0],[s,c,0],[0,0,1]]        c = cos a, s = sin a
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace triadcal {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;

template <typename T>
Mat3<T> Rx(const T& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a), s = sin(a);
  Mat3<T> r;
  r << T(1), T(0), T(0), T(0), c, -s, T(0), s, c;
  return r;
}

template <typename T>
Mat3<T> Ry(const T& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a), s = sin(a);
  Mat3<T> r;
  r << c, T(0), s, T(0), T(1), T(0), -s, T(0), c;
  return r;
}

template <typename T>
Mat3<T> Rz(const T& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a), s = sin(a);
  Mat3<T> r;
  r << c, -s, T(0), s, c, T(0), T(0), T(0), T(1);
  return r;
}

}  // namespace triadcal
