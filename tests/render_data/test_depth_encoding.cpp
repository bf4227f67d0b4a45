// Depth encodings for network input (render_channels.h): every encoding maps the near plane to
// 0 and the far plane and sky to 1, stays finite on extreme planes, and means what it says.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "render_data/render_channels.h"

using namespace cgsr;

namespace {
const float kInf = std::numeric_limits<float>::infinity();

torch::Tensor depths(std::initializer_list<float> z) { return torch::tensor(std::vector<float>(z)).view({1, 1, -1}); }
}  // namespace

TEST(DepthEncoding, NamesRoundTrip) {
  for (const auto& name : EnumNames<DepthEncoding>::names())
    EXPECT_EQ(enum_name(enum_from_name<DepthEncoding>(name)), name);
  try {
    enum_from_name<DepthEncoding>("logarithmic");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("log, linear, zbuffer"), std::string::npos) << e.what();
  }
}

TEST(DepthEncoding, LogSpendsEqualStepsPerOctave) {
  const double near = 0.05, far = 500;
  const auto v = encode_depth(depths({0.05f, 5.f, 500.f, kInf, 0.f, 1e9f}), near, far, DepthEncoding::Log);
  EXPECT_NEAR(v[0][0][0].item<float>(), 0.f, 1e-6);
  EXPECT_NEAR(v[0][0][1].item<float>(), 0.5f, 1e-6);  // the geometric middle of near and far
  EXPECT_NEAR(v[0][0][2].item<float>(), 1.f, 1e-6);
  EXPECT_EQ(v[0][0][3].item<float>(), 1.f);  // sky
  EXPECT_EQ(v[0][0][4].item<float>(), 0.f);  // before the near plane
  EXPECT_EQ(v[0][0][5].item<float>(), 1.f);  // beyond the far plane
  // Where the z-buffer value is above 0.95 (beyond 1 m here), the log encoding still spans most of [0,1].
  const auto room = depths({1.f, 10.f});
  const auto zb = encode_depth(room, near, far, DepthEncoding::ZBuffer);
  const auto lg = encode_depth(room, near, far, DepthEncoding::Log);
  EXPECT_LT((zb[0][0][1] - zb[0][0][0]).item<float>(), 0.05f);
  EXPECT_GT((lg[0][0][1] - lg[0][0][0]).item<float>(), 0.2f);
}

TEST(DepthEncoding, LinearAndZBuffer) {
  const auto z = depths({1.f, 250.f, kInf});
  const auto lin = encode_depth(z, 0.05, 500, DepthEncoding::Linear);
  EXPECT_NEAR(lin[0][0][0].item<float>(), 1.f / 500, 1e-7);
  EXPECT_NEAR(lin[0][0][1].item<float>(), 0.5f, 1e-6);
  EXPECT_EQ(lin[0][0][2].item<float>(), 1.f);
  EXPECT_TRUE(torch::equal(encode_depth(z, 0.05, 500, DepthEncoding::ZBuffer), normalize_depth(z, 0.05, 500)));
}

TEST(DepthEncoding, ExtremePlanesStayFiniteAndOrdered) {
  const auto z = depths({0.f, 1e-3f, 1.f, 1e3f, 1e6f, kInf});
  for (const auto& name : EnumNames<DepthEncoding>::names()) {
    SCOPED_TRACE(name);
    const auto v = encode_depth(z, 1e-3, 1e6, enum_from_name<DepthEncoding>(name));
    EXPECT_TRUE(torch::isfinite(v).all().item<bool>());
    EXPECT_GE(v.min().item<float>(), 0.f);
    EXPECT_LE(v.max().item<float>(), 1.f);
    const auto steps = v.flatten().slice(0, 1) - v.flatten().slice(0, 0, -1);
    EXPECT_GE(steps.min().item<float>(), 0.f);  // monotonic in depth
  }
  // The log encoding separates a metre from a kilometre even with a 1e9 range of planes.
  const auto lg = encode_depth(z, 1e-3, 1e6, DepthEncoding::Log);
  EXPECT_NEAR(lg[0][0][2].item<float>(), 3.f / 9, 1e-5);
  EXPECT_NEAR(lg[0][0][3].item<float>(), 6.f / 9, 1e-5);
}

TEST(DepthEncoding, BadPlanesAreErrors) {
  const auto z = depths({1.f});
  EXPECT_THROW(encode_depth(z, 0, 10, DepthEncoding::Log), Error);
  EXPECT_THROW(encode_depth(z, 10, 1, DepthEncoding::Linear), Error);
  EXPECT_THROW(encode_depth(z, 0.1, std::numeric_limits<double>::infinity(), DepthEncoding::Log), Error);
}
