#pragma once
// Rigid transforms. A transform T_a_b maps points from frame b into frame a: p_a = T_a_b * p_b.
// Twists xi = (v, w) in se(3): translation part first (metres), rotation part second (radians).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ff {

using SE3 = Eigen::Isometry3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d skew(const Eigen::Vector3d& w);
// Exponential map of se(3) (closed form, exact also for small angles).
SE3 expSE3(const Vector6d& xi);
// Logarithm, inverse of expSE3 for rotation angles below pi.
Vector6d logSE3(const SE3& T);

// TUM trajectory convention: translation then quaternion (qx, qy, qz, qw).
SE3 poseFromTranslationQuaternion(const Eigen::Vector3d& t, const Eigen::Quaterniond& q);

// The nearest proper rigid transform (rotation re-orthonormalised through a unit quaternion):
// long chains of products drift off SO(3), and Isometry3d::inverse() assumes R^-1 = R^T.
SE3 orthonormalized(const SE3& T);

double rotationAngleDeg(const SE3& T);
double translationNorm(const SE3& T);

// Interpolates between two poses: translation linearly, rotation by slerp. s in [0, 1].
SE3 interpolate(const SE3& a, const SE3& b, double s);

}  // namespace ff
