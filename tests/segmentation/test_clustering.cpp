#include <gtest/gtest.h>

#include <map>
#include <set>

#include "../flow/analytic_scene.h"
#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/clustering.h"

namespace ff {
namespace {

using testing::AnalyticScene;

TEST(ClustererFactory, UnknownBackendIsInputError) {
  nlohmann::json j = ClusteringConfig{};
  j["backend"] = "slic";
  try {
    j.get<ClusteringConfig>();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("clustering.backend"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("kmeans"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("supervoxel"), std::string::npos) << e.what();
  }
  ClusteringConfig c;
  c.kmeans_clusters = 0;
  EXPECT_THROW(makeClusterer(c), InputError);
}

class ClusteringBackends : public ::testing::TestWithParam<ClusteringBackend> {
 protected:
  std::unique_ptr<Clusterer> make() {
    ClusteringConfig c;
    c.backend = GetParam();
    return makeClusterer(c);
  }
};

void checkGraphInvariants(const ClusterGraph& g, const cv::Mat& depth) {
  ASSERT_EQ(g.labels.type(), CV_32SC1);
  ASSERT_EQ(g.labels.size(), depth.size());
  ASSERT_EQ(static_cast<int>(g.sizes.size()), g.num_clusters);
  ASSERT_EQ(static_cast<int>(g.mean_depth.size()), g.num_clusters);
  ASSERT_EQ(static_cast<int>(g.centroids.size()), g.num_clusters);
  std::vector<int> counted(g.num_clusters, 0);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const int l = g.labels.at<int>(v, u);
      if (depth.at<float>(v, u) > 0) {
        ASSERT_GE(l, 0) << "pixel with depth has no cluster at " << u << "," << v;
        ASSERT_LT(l, g.num_clusters);
        ++counted[l];
      } else {
        ASSERT_EQ(l, -1) << "pixel without depth has a cluster at " << u << "," << v;
      }
    }
  for (int c = 0; c < g.num_clusters; ++c) {
    EXPECT_EQ(counted[c], g.sizes[c]);
    EXPECT_GT(g.sizes[c], 0);
    EXPECT_NEAR(g.centroids[c].z(), g.mean_depth[c], 1e-3);
  }
  std::set<std::pair<int, int>> seen;
  for (const auto& [i, j] : g.edges) {
    EXPECT_LT(i, j);
    EXPECT_GE(i, 0);
    EXPECT_LT(j, g.num_clusters);
    EXPECT_TRUE(seen.insert({i, j}).second) << "duplicate edge " << i << "-" << j;
  }
}

TEST_P(ClusteringBackends, EveryPixelWithDepthGetsAClusterAndEdgesAreUnique) {
  const auto scene = AnalyticScene::make(160, 120);
  auto view = scene.render(SE3::Identity());
  // Holes, as the Kinect has.
  cv::rectangle(view.frame.depth, cv::Rect(10, 10, 12, 7), cv::Scalar(0), cv::FILLED);
  view.frame.depth.at<float>(60, 100) = 0;
  const ClusterGraph g = make()->cluster(view.frame, scene.camera);
  checkGraphInvariants(g, view.frame.depth);
  EXPECT_GT(g.num_clusters, 10);
  EXPECT_GT(g.edges.size(), static_cast<size_t>(g.num_clusters));
}

TEST_P(ClusteringBackends, TwoPlanesAtDifferentDepthsNeverShareAClusterOrAnEdge) {
  const CameraIntrinsics cam{130, 130, 79.5, 59.5, 160, 120};
  RgbdFrame f;
  f.depth = cv::Mat(120, 160, CV_32F, cv::Scalar(2.0f));
  f.depth(cv::Rect(0, 0, 70, 120)).setTo(1.0f);
  f.intensity = cv::Mat(120, 160, CV_32F);
  cv::randu(f.intensity, 0.f, 1.f);
  const ClusterGraph g = make()->cluster(f, cam);
  checkGraphInvariants(g, f.depth);
  std::vector<int> near(g.num_clusters, 0), far(g.num_clusters, 0);
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) ++(u < 70 ? near : far)[g.labels.at<int>(v, u)];
  for (int c = 0; c < g.num_clusters; ++c) EXPECT_TRUE(near[c] == 0 || far[c] == 0) << "cluster " << c;
  for (const auto& [i, j] : g.edges) EXPECT_EQ(near[i] > 0, near[j] > 0) << "edge across the depth jump";
}

TEST_P(ClusteringBackends, ObjectIsCoveredByClustersThatStayInside) {
  const auto scene = AnalyticScene::make(160, 120);
  const auto view = scene.render(SE3::Identity());
  const ClusterGraph g = make()->cluster(view.frame, scene.camera);
  std::vector<int> inside(g.num_clusters, 0);
  int box_pixels = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u)
      if (view.mask.at<uchar>(v, u)) {
        ++inside[g.labels.at<int>(v, u)];
        ++box_pixels;
      }
  int covered = 0;  // box pixels in clusters that are >= 90 % inside the box
  for (int c = 0; c < g.num_clusters; ++c)
    if (inside[c] >= 0.9 * g.sizes[c]) covered += inside[c];
  EXPECT_GT(covered, 0.9 * box_pixels) << covered << " of " << box_pixels;
}

INSTANTIATE_TEST_SUITE_P(Backends, ClusteringBackends,
                         ::testing::Values(ClusteringBackend::KMeans, ClusteringBackend::Supervoxel),
                         [](const auto& info) { return enumName(info.param); });

TEST(Clustering, RejectsBadInput) {
  auto c = makeClusterer(ClusteringConfig{});
  RgbdFrame f;
  f.depth = cv::Mat(120, 160, CV_32F, cv::Scalar(1.0f));
  EXPECT_THROW(c->cluster(f, CameraIntrinsics{100, 100, 80, 60, 320, 240}), InputError);
  f.depth = cv::Mat(120, 160, CV_16U, cv::Scalar(1));
  EXPECT_THROW(c->cluster(f, CameraIntrinsics{100, 100, 80, 60, 160, 120}), InputError);
}

TEST(Clustering, NoDepthGivesNoClusters) {
  RgbdFrame f;
  f.depth = cv::Mat(60, 80, CV_32F, cv::Scalar(0.0f));
  f.intensity = cv::Mat(60, 80, CV_32F, cv::Scalar(0.5f));
  for (const ClusteringBackend backend : {ClusteringBackend::KMeans, ClusteringBackend::Supervoxel}) {
    ClusteringConfig c;
    c.backend = backend;
    const ClusterGraph g = makeClusterer(c)->cluster(f, CameraIntrinsics{60, 60, 40, 30, 80, 60});
    EXPECT_EQ(g.num_clusters, 0) << enumName(backend);
    EXPECT_TRUE(g.edges.empty()) << enumName(backend);
  }
}

}  // namespace
}  // namespace ff
