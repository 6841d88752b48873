#include "flowfusion/core/se3.h"

#include <cmath>

namespace ff {

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

SE3 expSE3(const Vector6d& xi) {
  const Eigen::Vector3d v = xi.head<3>();
  const Eigen::Vector3d w = xi.tail<3>();
  const double theta = w.norm();
  const Eigen::Matrix3d W = skew(w);
  double a, b, c;  // sin(t)/t, (1-cos t)/t^2, (t - sin t)/t^3
  if (theta < 1e-5) {
    const double t2 = theta * theta;
    a = 1.0 - t2 / 6.0;
    b = 0.5 - t2 / 24.0;
    c = 1.0 / 6.0 - t2 / 120.0;
  } else {
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / (theta * theta);
    c = (theta - std::sin(theta)) / (theta * theta * theta);
  }
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  SE3 T = SE3::Identity();
  T.linear() = I + a * W + b * W * W;
  T.translation() = (I + b * W + c * W * W) * v;
  return T;
}

Vector6d logSE3(const SE3& T) {
  const Eigen::AngleAxisd aa(T.rotation());
  const Eigen::Vector3d w = aa.axis() * aa.angle();
  const double theta = aa.angle();
  const Eigen::Matrix3d W = skew(w);
  Eigen::Matrix3d Vinv = Eigen::Matrix3d::Identity() - 0.5 * W;
  if (theta > 1e-5) {
    const double k = (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / (theta * theta);
    Vinv += k * W * W;
  } else {
    Vinv += (1.0 / 12.0) * W * W;
  }
  Vector6d xi;
  xi.head<3>() = Vinv * T.translation();
  xi.tail<3>() = w;
  return xi;
}

SE3 poseFromTranslationQuaternion(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  SE3 T = SE3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

SE3 orthonormalized(const SE3& T) {
  SE3 out = SE3::Identity();
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  out.translation() = T.translation();
  return out;
}

double rotationAngleDeg(const SE3& T) {
  const double c = std::clamp((T.rotation().trace() - 1.0) * 0.5, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

double translationNorm(const SE3& T) { return T.translation().norm(); }

SE3 interpolate(const SE3& a, const SE3& b, double s) {
  const Eigen::Quaterniond qa(a.rotation()), qb(b.rotation());
  SE3 T = SE3::Identity();
  T.linear() = qa.slerp(s, qb).toRotationMatrix();
  T.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return T;
}

}  // namespace ff
