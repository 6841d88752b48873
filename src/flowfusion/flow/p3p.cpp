#include "flowfusion/flow/p3p.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ff {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// The real roots of x^3 + a x^2 + b x + c (Cardano, or the trigonometric form for three), each
// polished by Newton steps. Returns how many (1 or 3).
int realCubicRoots(double a, double b, double c, std::array<double, 3>& roots) {
  const double p = b - a * a / 3, q = 2 * a * a * a / 27 - a * b / 3 + c;
  const double disc = q * q / 4 + p * p * p / 27;
  int n = 1;
  if (disc >= 0) {
    const double s = std::sqrt(disc);
    roots[0] = std::cbrt(-q / 2 + s) + std::cbrt(-q / 2 - s) - a / 3;
  } else {  // p < 0
    const double m = 2 * std::sqrt(-p / 3);
    const double theta = std::acos(std::clamp(3 * q / (p * m), -1.0, 1.0)) / 3;
    for (int k = 0; k < 3; ++k) roots[k] = m * std::cos(theta - 2 * std::numbers::pi * k / 3) - a / 3;
    n = 3;
  }
  for (int k = 0; k < n; ++k)
    for (int step = 0; step < 2; ++step) {
      const double x = roots[k], f = ((x + a) * x + b) * x + c, df = (3 * x + 2 * a) * x + b;
      if (df != 0) roots[k] = x - f / df;
    }
  return n;
}

// The adjugate's rows of a 3x3 matrix are the cross products of its columns.
Matrix3d adjugate(const Matrix3d& m) {
  Matrix3d adj;
  adj.row(0) = m.col(1).cross(m.col(2)).transpose();
  adj.row(1) = m.col(2).cross(m.col(0)).transpose();
  adj.row(2) = m.col(0).cross(m.col(1)).transpose();
  return adj;
}

// The distances between the three points and the cosines between the rays, written as
// lambda_i^2 + lambda_j^2 + b_ij lambda_i lambda_j = a_ij for the depths lambda along unit rays.
struct P3PEquations {
  double a12, a13, a23, b12, b13, b23;

  Vector3d residual(const Vector3d& l) const {
    return {l[0] * l[0] + l[1] * l[1] + b12 * l[0] * l[1] - a12, l[0] * l[0] + l[2] * l[2] + b13 * l[0] * l[2] - a13,
            l[1] * l[1] + l[2] * l[2] + b23 * l[1] * l[2] - a23};
  }
  // The depths along direction d (up to sign and scale) that fit the distances best, all positive.
  bool scaleToDistances(const Vector3d& d, Vector3d& lambda) const {
    const Vector3d r = residual(d) + Vector3d(a12, a13, a23);  // |d_i y_i - d_j y_j|^2 >= 0 each
    const double sum = r.sum();
    if (!(sum > 0)) return false;
    const double k = std::copysign(std::sqrt((a12 + a13 + a23) / sum), d.sum());
    lambda = k * d;
    return lambda.minCoeff() > 0;
  }
  // Gauss-Newton steps on the three equations while they reduce the residual.
  void refine(Vector3d& l) const {
    double err = residual(l).squaredNorm();
    for (int it = 0; it < 5 && err > 0; ++it) {
      Matrix3d J;
      J << 2 * l[0] + b12 * l[1], 2 * l[1] + b12 * l[0], 0,  //
          2 * l[0] + b13 * l[2], 0, 2 * l[2] + b13 * l[0],    //
          0, 2 * l[1] + b23 * l[2], 2 * l[2] + b23 * l[1];
      const double det = J.determinant();
      if (!(std::abs(det) > 0)) return;
      const Vector3d next = l - J.inverse() * residual(l);
      const double next_err = residual(next).squaredNorm();
      if (!(next_err < err)) return;
      l = next;
      err = next_err;
    }
  }
};

// Of the pencil P + gamma R, the member (a degenerate conic of the depths' directions) that is a
// real pair of planes, the most open one when there are several: its eigenvalues ascending and
// eigenvectors, and gamma.
bool degeneratePlanePair(const Matrix3d& P, const Matrix3d& R, Eigen::SelfAdjointEigenSolver<Matrix3d>& best,
                         double& best_gamma) {
  const Matrix3d adj_P = adjugate(P), adj_R = adjugate(R);
  // det(P + gamma R) = det R gamma^3 + tr(adj(R) P) gamma^2 + tr(adj(P) R) gamma + det P.
  const double c3 = R.col(0).dot(adj_R.row(0)), c0 = P.col(0).dot(adj_P.row(0));
  const double c2 = (adj_R * P).trace(), c1 = (adj_P * R).trace();
  if (!(std::abs(c3) > 0)) return false;
  std::array<double, 3> gamma;
  const int n = realCubicRoots(c2 / c3, c1 / c3, c0 / c3, gamma);
  double best_openness = 0;
  for (int k = 0; k < n; ++k) {
    Eigen::SelfAdjointEigenSolver<Matrix3d> es;
    es.computeDirect(P + gamma[k] * R);
    const Vector3d& ev = es.eigenvalues();
    if (!(ev[0] < 0 && ev[2] > 0)) continue;
    const double openness = std::min(-ev[0], ev[2]) / std::max(-ev[0], ev[2]);
    if (openness > best_openness) {
      best_openness = openness;
      best = es;
      best_gamma = gamma[k];
    }
  }
  return best_openness > 0;
}

// The directions lambda = alpha v + beta u (up to two) on which q(lambda) = lambda^T Q lambda = 0;
// with `complex_pairs`, for a complex pair the direction of their real part.
int homogeneousRoots(const Matrix3d& Q, const Vector3d& v, const Vector3d& u, bool complex_pairs,
                     std::array<Vector3d, 2>& dirs) {
  const double A = v.dot(Q * v), B = v.dot(Q * u), C = u.dot(Q * u);
  const double disc = B * B - A * C;
  if (!(disc >= 0)) {
    if (!complex_pairs || !(A != 0)) return 0;
    dirs[0] = -B * v + A * u;
    return 1;
  }
  const double q = -(B + std::copysign(std::sqrt(disc), B));  // no cancellation
  int n = 0;
  for (const auto& [alpha, beta] : {std::pair{q, A}, std::pair{C, q}})
    if (alpha != 0 || beta != 0) dirs[n++] = alpha * v + beta * u;
  return n;
}

// solveP3P, and with `complex_pairs` also the poses from the real parts of complex pairs of
// solutions, which fit the three rays only approximately.
P3PSolutions solveP3PPairs(const std::array<Vector3d, 3>& points, const std::array<Vector3d, 3>& rays,
                           bool complex_pairs) {
  P3PSolutions out;
  std::array<Vector3d, 3> y;
  for (int i = 0; i < 3; ++i) {
    if (!points[i].allFinite() || !rays[i].allFinite() || !(rays[i].norm() > 0)) return out;
    y[i] = rays[i].normalized();
  }
  // Angles below this (radians) make rays parallel and points collinear.
  constexpr double kMinSin = 1e-10;
  for (const auto& [i, j] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}})
    if (!(y[i].cross(y[j]).norm() > kMinSin)) return out;
  const Vector3d d12 = points[0] - points[1], d13 = points[0] - points[2], d23 = points[1] - points[2];
  const P3PEquations eq{d12.squaredNorm(), d13.squaredNorm(), d23.squaredNorm(),
                        -2 * y[0].dot(y[1]),  -2 * y[0].dot(y[2]),  -2 * y[1].dot(y[2])};
  const Vector3d normal = d12.cross(d13);
  if (!(normal.norm() > kMinSin * std::sqrt(eq.a12 * eq.a13))) return out;

  // Two homogeneous quadrics in the depths (the scale eliminated): a23 * eq12 - a12 * eq23 and
  // a23 * eq13 - a13 * eq23. Their pencil holds a pair of planes through all common solutions.
  Matrix3d D1, D2;
  D1 << eq.a23, eq.a23 * eq.b12 / 2, 0,                           //
      eq.a23 * eq.b12 / 2, eq.a23 - eq.a12, -eq.a12 * eq.b23 / 2,  //
      0, -eq.a12 * eq.b23 / 2, -eq.a12;
  D2 << eq.a23, 0, eq.a23 * eq.b13 / 2,  //
      0, -eq.a13, -eq.a13 * eq.b23 / 2,  //
      eq.a23 * eq.b13 / 2, -eq.a13 * eq.b23 / 2, eq.a23 - eq.a13;
  // The better conditioned cubic: the larger determinant leads.
  const bool swap = std::abs(D1.determinant()) > std::abs(D2.determinant());
  const Matrix3d& P = swap ? D2 : D1;
  const Matrix3d& R = swap ? D1 : D2;
  Eigen::SelfAdjointEigenSolver<Matrix3d> es;
  double gamma = 0;
  if (!degeneratePlanePair(P, R, es, gamma)) return out;
  const Vector3d& ev = es.eigenvalues();
  const Vector3d v_neg = es.eigenvectors().col(0), v_null = es.eigenvectors().col(1), v_pos = es.eigenvectors().col(2);
  const double s = std::sqrt(-ev[0] / ev[2]);
  // Intersected with the quadric of the pencil least like the plane pair.
  const Matrix3d& Q = std::abs(gamma) < 1 ? R : P;

  const Matrix3d X_inv = (Matrix3d() << d12, d13, normal).finished().inverse();
  for (const double sign : {1.0, -1.0}) {
    const Vector3d plane_normal = v_pos + sign * s * v_neg;
    std::array<Vector3d, 2> dirs;
    const int n = homogeneousRoots(Q, v_null, plane_normal.cross(v_null).normalized(), complex_pairs, dirs);
    for (int k = 0; k < n; ++k) {
      Vector3d lambda;
      if (!eq.scaleToDistances(dirs[k], lambda)) continue;
      eq.refine(lambda);
      if (!(lambda.minCoeff() > 0) || !lambda.allFinite()) continue;
      // The rotation takes the triangle's edges (and their normal) to the camera frame's.
      const Vector3d c1 = lambda[0] * y[0], e12 = c1 - lambda[1] * y[1], e13 = c1 - lambda[2] * y[2];
      SE3 T = SE3::Identity();
      T.linear() = (Matrix3d() << e12, e13, e12.cross(e13)).finished() * X_inv;
      T = orthonormalized(T);
      T.translation() = c1 - T.linear() * points[0];
      // (A complex pair's pose fits the rays only approximately: the points may fall behind.)
      const bool in_front = (T * points[1]).z() > 0 && (T * points[2]).z() > 0;
      if (in_front && T.matrix().allFinite()) out.T_cam_pts[out.size++] = T;
    }
  }
  return out;
}

}  // namespace

P3PSolutions solveP3P(const std::array<Vector3d, 3>& points, const std::array<Vector3d, 3>& rays) {
  return solveP3PPairs(points, rays, false);
}

std::optional<SE3> solveP3PChoosingByFourth(const std::array<Vector3d, 4>& points,
                                           const std::array<Eigen::Vector2d, 4>& pixels,
                                           const CameraIntrinsics& camera) {
  std::array<Vector3d, 3> rays;
  for (int i = 0; i < 3; ++i)
    rays[i] = Vector3d((pixels[i].x() - camera.cx) / camera.fx, (pixels[i].y() - camera.cy) / camera.fy, 1);
  const P3PSolutions solutions = solveP3PPairs({points[0], points[1], points[2]}, rays, true);
  std::optional<SE3> best;
  double best_error = std::numeric_limits<double>::infinity();
  for (int k = 0; k < solutions.size; ++k) {
    const Vector3d q = solutions.T_cam_pts[k] * points[3];
    if (!(q.z() > 0)) continue;
    const double error = (camera.project(q) - pixels[3]).squaredNorm();
    if (error < best_error) {
      best_error = error;
      best = solutions.T_cam_pts[k];
    }
  }
  return best;
}

}  // namespace ff
