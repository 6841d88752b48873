#include <gtest/gtest.h>

#include "flowfusion/core/se3.h"

namespace ff {
namespace {

TEST(Se3, ExpLogRoundTrip) {
  for (double scale : {1e-9, 1e-4, 0.1, 1.0, 2.5}) {
    Vector6d xi;
    xi << 0.3, -0.2, 0.5, 0.4, -0.7, 0.2;
    xi *= scale;
    const Vector6d back = logSE3(expSE3(xi));
    EXPECT_LT((back - xi).norm(), 1e-9 * std::max(1.0, xi.norm())) << "scale " << scale;
  }
}

TEST(Se3, ExpOfPureTranslationIsTranslation) {
  Vector6d xi = Vector6d::Zero();
  xi.head<3>() << 1, 2, 3;
  const SE3 T = expSE3(xi);
  EXPECT_TRUE(T.linear().isIdentity(1e-12));
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
}

TEST(Se3, InterpolateEndpointsAndMidpoint) {
  Vector6d xi;
  xi << 0.2, 0, 0, 0, 0, 0.4;
  const SE3 a = SE3::Identity(), b = expSE3(xi);
  EXPECT_TRUE(interpolate(a, b, 0).isApprox(a));
  EXPECT_TRUE(interpolate(a, b, 1).isApprox(b));
  EXPECT_NEAR(rotationAngleDeg(interpolate(a, b, 0.5)), 0.2 * 180 / M_PI, 1e-9);
}

}  // namespace
}  // namespace ff
