#include "flowfusion/synth/texture.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace ff::synth {

namespace {

constexpr int S = kTextureSize;

// Sum of tileable value-noise octaves, cell sizes (texels) from max_cell down to min_cell, each
// octave `gain` times the amplitude of the coarser one. gain 0.5 would be the smooth 1/f^2 power
// spectrum of classic fBm; natural images are closer to equal power per octave (1/f amplitude in
// 2D), so the materials use gains of about 0.6 to 0.85. aspect > 1 stretches cells along x (grain).
// Returns zero mean, unit standard deviation.
cv::Mat fractal(Rng& rng, int min_cell, int max_cell, double gain, int aspect = 1) {
  cv::Mat acc = cv::Mat::zeros(S, S, CV_32F);
  double amp = 1.0;
  for (int c = max_cell; c >= min_cell; c /= 2) {
    const int nx = std::max(2, S / std::min(S, c * aspect));
    const int ny = std::max(2, S / c);
    cv::Mat grid(ny, nx, CV_32F);
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) grid.at<float>(y, x) = static_cast<float>(rng.uniform(-1.0, 1.0));
    cv::Mat padded, up;
    cv::copyMakeBorder(grid, padded, 2, 2, 2, 2, cv::BORDER_WRAP);
    const int fx = S / nx, fy = S / ny;
    cv::resize(padded, up, cv::Size((nx + 4) * fx, (ny + 4) * fy), 0, 0, cv::INTER_CUBIC);
    acc += amp * up(cv::Rect(2 * fx, 2 * fy, S, S));
    amp *= gain;
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(acc, mean, stddev);
  acc = (acc - mean[0]) / std::max(1e-6, stddev[0]);
  return acc;
}

cv::Vec3f hsv(double h_deg, double s, double v) {
  h_deg = std::fmod(std::fmod(h_deg, 360.0) + 360.0, 360.0);
  const double c = v * s, hp = h_deg / 60.0, x = c * (1 - std::fabs(std::fmod(hp, 2.0) - 1));
  double r = 0, g = 0, b = 0;
  if (hp < 1) r = c, g = x;
  else if (hp < 2) r = x, g = c;
  else if (hp < 3) g = c, b = x;
  else if (hp < 4) g = x, b = c;
  else if (hp < 5) r = x, b = c;
  else r = c, b = x;
  const double m = v - c;
  return {static_cast<float>(b + m), static_cast<float>(g + m), static_cast<float>(r + m)};
}

cv::Scalar toScalar8(const cv::Vec3f& c) { return {c[0] * 255.0, c[1] * 255.0, c[2] * 255.0}; }

// base colour modulated by a luminance field (1 + contrast * L) and slow per-channel chroma drift.
cv::Mat modulate(const cv::Vec3f& base, const cv::Mat& L, double contrast, Rng& rng, double chroma) {
  cv::Mat cb = fractal(rng, 32, 256, 0.7), cr = fractal(rng, 32, 256, 0.7);
  cv::Mat out(S, S, CV_32FC3);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      const float l = 1.0f + static_cast<float>(contrast) * L.at<float>(y, x);
      const float kb = 1.0f + static_cast<float>(chroma) * cb.at<float>(y, x);
      const float kr = 1.0f + static_cast<float>(chroma) * cr.at<float>(y, x);
      out.at<cv::Vec3f>(y, x) = cv::Vec3f(base[0] * l * kb, base[1] * l, base[2] * l * kr);
    }
  return out;
}

// Smooth organic patches (stains, wear): where a low-frequency field exceeds a threshold.
cv::Mat patches(Rng& rng, double threshold) {
  cv::Mat f = fractal(rng, 4, 128, 0.6), out;
  f.forEach<float>([&](float& v, const int*) {
    const double s = std::clamp((v - threshold) / 0.4, 0.0, 1.0);
    v = static_cast<float>(s * s * (3 - 2 * s));
  });
  return f;
}

cv::Mat multiply(const cv::Mat& rgb, const cv::Mat& gray, double k) {
  cv::Mat out = rgb.clone();
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) out.at<cv::Vec3f>(y, x) *= 1.0f + static_cast<float>(k) * gray.at<float>(y, x);
  return out;
}

// Antialiased shapes are drawn on an 8-bit canvas (OpenCV antialiases 8-bit images only).
cv::Mat to8(const cv::Mat& f) {
  cv::Mat out;
  f.convertTo(out, CV_8UC3, 255.0);
  return out;
}
cv::Mat toF(const cv::Mat& b) {
  cv::Mat out;
  b.convertTo(out, CV_32FC3, 1.0 / 255.0);
  return out;
}

cv::Vec3f randomColour(Rng& rng, double smin, double smax, double vmin, double vmax) {
  return hsv(rng.uniform(0, 360), rng.uniform(smin, smax), rng.uniform(vmin, vmax));
}

void drawShapes(cv::Mat& canvas8, Rng& rng, int count, int min_size, int max_size, double smin, double vmin) {
  for (int i = 0; i < count; ++i) {
    const cv::Scalar colour = toScalar8(randomColour(rng, smin, 0.9, vmin, 0.95));
    const cv::Point c(rng.uniformInt(0, S - 1), rng.uniformInt(0, S - 1));
    const int a = rng.uniformInt(min_size, max_size), b = rng.uniformInt(min_size, max_size);
    switch (rng.uniformInt(0, 3)) {
      case 0: cv::rectangle(canvas8, cv::Rect(c.x - a / 2, c.y - b / 2, a, b), colour, cv::FILLED, cv::LINE_AA); break;
      case 1:
        cv::ellipse(canvas8, c, cv::Size(a / 2, b / 2), rng.uniform(0, 180), 0, 360, colour, cv::FILLED, cv::LINE_AA);
        break;
      case 2:
        cv::line(canvas8, c, c + cv::Point(a, b - max_size / 2), colour, rng.uniformInt(2, 6), cv::LINE_AA);
        break;
      default:
        cv::circle(canvas8, c, a / 2, colour, rng.uniformInt(2, 5), cv::LINE_AA);
        break;
    }
  }
}

cv::Mat plaster(Rng& rng, double sat_max, double vmin, double vmax, double contrast) {
  const cv::Vec3f base = randomColour(rng, 0.02, sat_max, vmin, vmax);
  cv::Mat img = modulate(base, fractal(rng, 1, 256, rng.uniform(0.62, 0.72)), contrast, rng, 0.03);
  return multiply(img, patches(rng, rng.uniform(1.0, 1.6)), -rng.uniform(0.04, 0.1));
}

cv::Mat wood(Rng& rng) {
  const cv::Vec3f base = hsv(rng.uniform(18, 38), rng.uniform(0.4, 0.75), rng.uniform(0.35, 0.8));
  const cv::Mat warp = fractal(rng, 4, 256, 0.55, 8);
  const cv::Mat fine = fractal(rng, 1, 64, 0.75);
  const int planks = 12 + 4 * rng.uniformInt(0, 2);
  std::vector<double> tone(planks), joint(planks);
  for (int p = 0; p < planks; ++p) {
    tone[p] = 1.0 + 0.12 * rng.normal();
    joint[p] = rng.uniform(0, S);
  }
  const double period = rng.uniform(5, 9);  // texels between grain lines
  cv::Mat img(S, S, CV_32FC3);
  for (int y = 0; y < S; ++y) {
    const int p = y * planks / S;
    const double within = y * planks / static_cast<double>(S) - p;
    for (int x = 0; x < S; ++x) {
      const double g = 0.5 + 0.5 * std::sin(2 * M_PI * (y / period + 1.8 * warp.at<float>(y, x)));
      double k = tone[p] * (1 - 0.14 * g) * (1 + 0.06 * fine.at<float>(y, x));
      const double dx = std::fabs(std::remainder(x - joint[p], static_cast<double>(S)));
      if (within * S / planks < 1.0 || dx < 1.0) k *= 0.45;  // gaps between planks: dark edges
      img.at<cv::Vec3f>(y, x) = base * static_cast<float>(k);
    }
  }
  return img;
}

cv::Mat fabric(Rng& rng) {
  const cv::Vec3f base = randomColour(rng, 0.2, 0.65, 0.25, 0.6);
  cv::Mat img = modulate(base, fractal(rng, 1, 128, rng.uniform(0.78, 0.88)), 0.16, rng, 0.05);
  return multiply(img, fractal(rng, 16, 256, 0.6), 0.1);
}

cv::Mat painted(Rng& rng) {
  const cv::Vec3f base = randomColour(rng, 0.05, 0.6, 0.3, 0.85);
  cv::Mat img8 = to8(modulate(base, fractal(rng, 1, 256, 0.65), 0.06, rng, 0.03));
  // Panel and door outlines: straight edges at furniture scale.
  for (int i = rng.uniformInt(2, 4); i > 0; --i) {
    const cv::Rect r(rng.uniformInt(0, S / 2), rng.uniformInt(0, S / 2), rng.uniformInt(60, 250),
                     rng.uniformInt(60, 250));
    cv::rectangle(img8, r, toScalar8(base * 0.55f), 2, cv::LINE_AA);
    cv::circle(img8, cv::Point(r.x + r.width - 12, r.y + r.height / 2), 5, toScalar8(base * 0.3f), cv::FILLED,
               cv::LINE_AA);
  }
  return multiply(toF(img8), patches(rng, 1.4), -0.08);
}

cv::Mat poster(Rng& rng) {
  const cv::Mat hue = fractal(rng, 8, 256, 0.6);
  const double h0 = rng.uniform(0, 360);
  cv::Mat bg(S, S, CV_32FC3);
  const cv::Mat L = fractal(rng, 1, 256, 0.7);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x)
      bg.at<cv::Vec3f>(y, x) = hsv(h0 + 60 * hue.at<float>(y, x), 0.5, std::clamp(0.55 + 0.2 * L.at<float>(y, x), 0.05, 1.0));
  cv::Mat img8 = to8(bg);
  drawShapes(img8, rng, rng.uniformInt(12, 30), 15, 160, 0.3, 0.15);
  return multiply(toF(img8), fractal(rng, 1, 32, 0.8), 0.04);
}

cv::Mat cardboard(Rng& rng) {
  const cv::Vec3f base = hsv(rng.uniform(26, 38), rng.uniform(0.42, 0.6), rng.uniform(0.5, 0.72));
  cv::Mat img8 = to8(modulate(base, fractal(rng, 1, 128, 0.7), 0.08, rng, 0.03));
  const int band = rng.uniformInt(0, S - 40);
  cv::rectangle(img8, cv::Rect(0, band, S, rng.uniformInt(20, 35)), toScalar8(hsv(35, 0.25, 0.85)), cv::FILLED,
                cv::LINE_AA);
  for (int i = rng.uniformInt(3, 8); i > 0; --i) {
    const cv::Point p(rng.uniformInt(0, S - 100), rng.uniformInt(0, S - 30));
    if (rng.chance(0.5))
      cv::rectangle(img8, cv::Rect(p.x, p.y, rng.uniformInt(20, 90), rng.uniformInt(8, 30)), toScalar8(base * 0.3f),
                    rng.chance(0.5) ? cv::FILLED : 2, cv::LINE_AA);
    else
      cv::putText(img8, "FRAGILE", p, cv::FONT_HERSHEY_SIMPLEX, rng.uniform(0.5, 1.2), toScalar8(base * 0.25f), 2,
                  cv::LINE_AA);
  }
  return toF(img8);
}

cv::Mat clothing(Rng& rng) {
  const cv::Vec3f base = randomColour(rng, 0.2, 0.8, 0.15, 0.7);
  cv::Mat img = modulate(base, fractal(rng, 1, 128, 0.72), 0.12, rng, 0.04);
  if (rng.chance(0.5)) {
    const cv::Vec3f second = randomColour(rng, 0.2, 0.8, 0.15, 0.8);
    const double period = rng.uniform(16, 48), duty = rng.uniform(0.2, 0.6);
    for (int y = 0; y < S; ++y) {
      // Stripes repeat an integer number of times per tile so the tile stays seamless.
      const double phase = std::fmod(y / (S / std::round(S / period)), 1.0);
      if (phase < duty)
        for (int x = 0; x < S; ++x) {
          cv::Vec3f& c = img.at<cv::Vec3f>(y, x);
          c = cv::Vec3f(c[0] / base[0] * second[0], c[1] / std::max(base[1], 1e-3f) * second[1],
                        c[2] / std::max(base[2], 1e-3f) * second[2]);
        }
    }
  }
  return multiply(img, fractal(rng, 8, 128, 0.6), 0.15);  // folds
}

cv::Mat skin(Rng& rng) {
  const cv::Vec3f base = hsv(rng.uniform(15, 30), rng.uniform(0.3, 0.55), rng.uniform(0.45, 0.85));
  return modulate(base, fractal(rng, 1, 128, 0.65), 0.05, rng, 0.03);
}

}  // namespace

const char* materialName(Material m) {
  switch (m) {
    case Material::Plaster: return "plaster";
    case Material::Ceiling: return "ceiling";
    case Material::Wood: return "wood";
    case Material::Fabric: return "fabric";
    case Material::Painted: return "painted";
    case Material::Poster: return "poster";
    case Material::Cardboard: return "cardboard";
    case Material::Clothing: return "clothing";
    case Material::Skin: return "skin";
  }
  return "?";
}

Texture makeTexture(Material material, Rng& rng) {
  cv::Mat img;
  switch (material) {
    case Material::Plaster: img = plaster(rng, 0.2, 0.55, 0.8, rng.uniform(0.05, 0.1)); break;
    case Material::Ceiling: img = plaster(rng, 0.04, 0.75, 0.85, 0.04); break;
    case Material::Wood: img = wood(rng); break;
    case Material::Fabric: img = fabric(rng); break;
    case Material::Painted: img = painted(rng); break;
    case Material::Poster: img = poster(rng); break;
    case Material::Cardboard: img = cardboard(rng); break;
    case Material::Clothing: img = clothing(rng); break;
    case Material::Skin: img = skin(rng); break;
  }
  cv::Mat clamped = cv::min(cv::max(img, cv::Scalar::all(0.0)), cv::Scalar::all(1.0));
  return Texture(clamped, kTexelMetres);
}

Texture::Texture(const cv::Mat& level0, double texel_m) : texel_m_(texel_m) {
  levels_.push_back(level0);
  while (levels_.back().cols > 1) {
    cv::Mat half;
    // Exact 2x2 averaging: no border handling, so the tile stays seamless at every level.
    cv::resize(levels_.back(), half, cv::Size(levels_.back().cols / 2, levels_.back().rows / 2), 0, 0,
               cv::INTER_AREA);
    levels_.push_back(half);
  }
}

cv::Vec3f Texture::bilinear(int level, double x, double y) const {
  const cv::Mat& m = levels_[level];
  const int mask = m.cols - 1;
  x -= 0.5;
  y -= 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
  const int x0 = static_cast<int>(static_cast<int64_t>(fx) & mask), y0 = static_cast<int>(static_cast<int64_t>(fy) & mask);
  const int x1 = (x0 + 1) & mask, y1 = (y0 + 1) & mask;
  const cv::Vec3f* r0 = m.ptr<cv::Vec3f>(y0);
  const cv::Vec3f* r1 = m.ptr<cv::Vec3f>(y1);
  return (r0[x0] * (1 - ax) + r0[x1] * ax) * (1 - ay) + (r1[x0] * (1 - ax) + r1[x1] * ax) * ay;
}

cv::Vec3f Texture::sample(double u_m, double v_m, double footprint_m) const {
  const float lod = std::clamp(std::log2(std::max(static_cast<float>(footprint_m / texel_m_), 1e-9f)), 0.0f,
                               static_cast<float>(levels_.size() - 1));
  const int l0 = static_cast<int>(lod);
  const int l1 = std::min(l0 + 1, static_cast<int>(levels_.size()) - 1);
  const float a = lod - static_cast<float>(l0);
  const double s0 = 1.0 / (texel_m_ * (1 << l0));
  const cv::Vec3f c0 = bilinear(l0, u_m * s0, v_m * s0);
  if (a <= 0.0f || l1 == l0) return c0;
  const double s1 = 0.5 * s0;
  return c0 * (1 - a) + bilinear(l1, u_m * s1, v_m * s1) * a;
}

}  // namespace ff::synth
