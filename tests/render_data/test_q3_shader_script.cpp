// Shader scripts: surfaceparms, stages, and how a shader is drawn without blending passes.
#include <gtest/gtest.h>

#include "render_data/q3/shader_script.h"
#include "tests/render_data/q3_test_map.h"

namespace cgsr::q3 {
namespace {

ShaderLibrary test_library() {
  const auto files = testing::test_map_files(testing::make_test_map());
  const auto& script = files.at("scripts/tiny.shader");
  ShaderLibrary lib;
  lib.add_script(std::string(script.begin(), script.end()), "tiny.shader");
  return lib;
}

TEST(Q3ShaderScript, ParsesTheTestShaders) {
  const ShaderLibrary lib = test_library();
  EXPECT_TRUE(lib.problems().empty());
  ASSERT_EQ(lib.size(), 3u);
  const ShaderDefinition* sky = lib.find("TEXTURES/TEST/SKY");
  ASSERT_NE(sky, nullptr);
  EXPECT_TRUE(sky->has("sky"));
  EXPECT_EQ(sky->sky_farbox, "-");
  ASSERT_EQ(sky->stages.size(), 1u);
  ASSERT_TRUE(sky->stages[0].constant_color.has_value());
  EXPECT_FLOAT_EQ((*sky->stages[0].constant_color)[2], 0.8f);
  EXPECT_EQ(sky->colour_stage(), nullptr);  // $whiteimage only
  EXPECT_EQ(classify(*sky), ShaderLook::Sky);

  const ShaderDefinition* glass = lib.find("textures/test/glass");
  ASSERT_NE(glass, nullptr);
  EXPECT_TRUE(glass->cull_none);
  EXPECT_EQ(glass->stages[0].blend_src, "gl_one");
  EXPECT_EQ(glass->stages[1].blend_src, "gl_dst_color");
  EXPECT_EQ(classify(*glass), ShaderLook::Transparent);

  const ShaderDefinition* grate = lib.find("textures/test/grate");
  ASSERT_NE(grate, nullptr);
  ASSERT_NE(grate->colour_stage(), nullptr);
  EXPECT_EQ(grate->colour_stage()->map, "textures/test/grate.tga");
  EXPECT_EQ(grate->colour_stage()->alpha_func, "ge128");
  EXPECT_EQ(grate->stages[1].rgb_gen, "identity");
  EXPECT_EQ(classify(*grate), ShaderLook::AlphaTested);
  EXPECT_EQ(lib.find("textures/test/floor"), nullptr);
}

TEST(Q3ShaderScript, LooksOfCommonShaderForms) {
  ShaderLibrary lib;
  lib.add_script(
      "a/opaque { { map $lightmap } { map a/opaque.tga\n blendFunc GL_DST_COLOR GL_ZERO } }\n"
      "a/nodraw\n{\n surfaceparm nodraw\n}\n"
      "a/fog { surfaceparm fog\n fogparms ( 1 1 1 ) 512 }\n"
      "a/empty { surfaceparm nolightmap }\n"
      "a/anim { { animMap 10 a/f1.tga a/f2.tga\n rgbGen vertex } }\n"
      "a/lit { { map a/lit.jpg\n blendFunc GL_ONE GL_ZERO } }\n",
      "forms.shader");
  EXPECT_TRUE(lib.problems().empty());
  EXPECT_EQ(classify(*lib.find("a/opaque")), ShaderLook::Opaque);
  EXPECT_EQ(lib.find("a/opaque")->colour_stage()->map, "a/opaque.tga");
  EXPECT_EQ(classify(*lib.find("a/nodraw")), ShaderLook::Invisible);
  EXPECT_EQ(classify(*lib.find("a/fog")), ShaderLook::Invisible);
  EXPECT_EQ(classify(*lib.find("a/empty")), ShaderLook::Invisible);
  EXPECT_EQ(lib.find("a/anim")->colour_stage()->map, "a/f1.tga");
  EXPECT_EQ(lib.find("a/anim")->colour_stage()->rgb_gen, "vertex");
  EXPECT_EQ(classify(*lib.find("a/lit")), ShaderLook::Opaque);  // GL_ONE GL_ZERO replaces: opaque
}

TEST(Q3ShaderScript, SyntaxErrorsKeepEarlierShadersAndAreRecorded) {
  ShaderLibrary lib;
  lib.add_script("good/one { { map good/one.tga } }\nbad/two { { map x.tga }\n", "broken.shader");
  EXPECT_NE(lib.find("good/one"), nullptr);
  EXPECT_EQ(lib.find("bad/two"), nullptr);
  ASSERT_EQ(lib.problems().size(), 1u);
  EXPECT_NE(lib.problems()[0].find("broken.shader"), std::string::npos);
  // A later definition of the same name replaces the earlier one.
  lib.add_script("good/one { surfaceparm nodraw }", "later.shader");
  EXPECT_EQ(classify(*lib.find("good/one")), ShaderLook::Invisible);
  lib.add_script("x /* never closed", "comment.shader");
  EXPECT_EQ(lib.problems().size(), 2u);
}

}  // namespace
}  // namespace cgsr::q3
