#pragma once
// Procedural surface textures with natural-image statistics (fractal value noise with a roughly
// 1/f amplitude spectrum, colour variation, blobs, edges, wood grain), tileable, with a mip
// pyramid so that distant surfaces are filtered instead of aliased.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "flowfusion/synth/random.h"

namespace ff::synth {

class Texture {
 public:
  // level0: CV_32FC3 BGR in [0, 1], square with a power-of-two side; texel_m: metres per texel.
  Texture(const cv::Mat& level0, double texel_m);

  // Colour at surface coordinates (metres), filtered over a footprint of footprint_m metres
  // (trilinear mip-mapping, wrapping at the tile border).
  cv::Vec3f sample(double u_m, double v_m, double footprint_m) const;
  const cv::Mat& image() const { return levels_.front(); }

 private:
  cv::Vec3f bilinear(int level, double x, double y) const;
  std::vector<cv::Mat> levels_;
  double texel_m_;
};

enum class Material { Plaster, Ceiling, Wood, Fabric, Painted, Poster, Cardboard, Clothing, Skin };
const char* materialName(Material m);

// Side of every texture tile in texels, and the texel size: a 2.56 m tile at 5 mm.
inline constexpr int kTextureSize = 512;
inline constexpr double kTexelMetres = 0.005;

Texture makeTexture(Material material, Rng& rng);

}  // namespace ff::synth
