// Rendering: the same image for any thread count and any structure, not blank, close to a committed
// low-resolution reference; heatmaps and PNG files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "accel/core/registry.h"
#include "tracer/heatmap.h"
#include "tracer/image.h"
#include "tracer/integrator.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

/// Every material and light on inline meshes only (so that the reference does not depend on the
/// generators): a floor, a rotated box, a mirror tetrahedron, a glass slab, a glossy box.
const char* kScene = R"(<scene>
  <camera><eye>0 2 6</eye><lookat>0 0.5 0</lookat><fov>45</fov><aperture>0.03</aperture></camera>
  <background>0.1 0.12 0.15</background>
  <ambient>0.03 0.03 0.03</ambient>
  <material name="white" type="diffuse"><color>0.7 0.7 0.7</color></material>
  <material name="red" type="diffuse"><color>0.8 0.2 0.1</color></material>
  <material name="chrome" type="mirror"/>
  <material name="glass" type="dielectric"><ior>1.5</ior></material>
  <material name="gold" type="glossy"><color>0.9 0.7 0.3</color><roughness>0.2</roughness></material>
  <light type="area"><corner>-1 4 -1</corner><edge1>2 0 0</edge1><edge2>0 0 2</edge2><radiance>6 6 6</radiance></light>
  <light type="point"><position>3 3 3</position><intensity>4 4 4</intensity></light>
  <mesh name="quad"><vertices>-1 0 -1 1 0 -1 1 0 1 -1 0 1</vertices><triangles>0 2 1 0 3 2</triangles></mesh>
  <mesh name="box">
    <vertices>-1 -1 -1 1 -1 -1 1 1 -1 -1 1 -1 -1 -1 1 1 -1 1 1 1 1 -1 1 1</vertices>
    <triangles>0 2 1 0 3 2 4 5 6 4 6 7 0 1 5 0 5 4 3 6 2 3 7 6 0 4 7 0 7 3 1 2 6 1 6 5</triangles>
  </mesh>
  <mesh name="tetra"><vertices>1 1 1 -1 -1 1 -1 1 -1 1 -1 -1</vertices><triangles>0 1 2 0 3 1 0 2 3 1 3 2</triangles></mesh>
  <instance mesh="quad" material="white"><scale>6 1 6</scale></instance>
  <instance mesh="box" material="red"><translate>-1.3 0.5 0</translate><rotate axis="Y">30</rotate><scale>0.5</scale></instance>
  <instance mesh="tetra" material="chrome"><translate>0.2 0.6 -1</translate><scale>0.6</scale></instance>
  <instance mesh="box" material="glass"><translate>0.6 0.4 1</translate><scale>0.4 0.4 0.1</scale></instance>
  <instance mesh="box" material="gold"><translate>1.6 0.35 -0.2</translate><rotate axis="1 1 0">45</rotate><scale>0.3 0.35 0.3</scale></instance>
</scene>)";

struct Fixture {
  std::shared_ptr<const Scene> scene = std::make_shared<const Scene>(parse_scene(kScene, "render.xml", "."));
  RenderOptions options() const {
    RenderOptions o;
    o.width = 40;
    o.height = 32;
    o.spp = 4;
    return o;
  }
  std::unique_ptr<Accelerator> accel(const std::string& name) const {
    auto a = make_scene_accelerator(scene, name, Params{});
    a->build();
    return a;
  }
};

bool same_bits(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(vec3)) == 0;
}

TEST(Render, SameImageForAnyThreadCount) {
  Fixture f;
  auto accel = f.accel("brute");
  RenderOptions o = f.options();
  o.threads = 1;
  const Image one = render(*f.scene, *accel, o);
  o.threads = 2;
  const Image two = render(*f.scene, *accel, o);
  EXPECT_TRUE(same_bits(one, two));
  o.seed = 2;
  EXPECT_FALSE(same_bits(one, render(*f.scene, *accel, o)));  // the seed matters
}

TEST(Render, SameImageForEveryStructure) {
  Fixture f;
  const Image expected = render(*f.scene, *f.accel("brute"), f.options());
  for (const AcceleratorInfo& info : accelerators()) {
    if (!info.make_for_instances || info.name.rfind("test-", 0) == 0) continue;
    EXPECT_TRUE(same_bits(expected, render(*f.scene, *f.accel(info.name), f.options()))) << info.name;
  }
}

TEST(Render, ImageIsNotBlankAndMatchesTheReference) {
  Fixture f;
  RenderOptions o = f.options();
  o.spp = 16;
  RenderCounts counts;
  const Image8 img = to_srgb8(render(*f.scene, *f.accel("brute"), o, &counts));
  EXPECT_EQ(counts.camera_rays, uint64_t(o.width) * uint64_t(o.height) * uint64_t(o.spp));
  EXPECT_GT(counts.shadow_rays, counts.camera_rays / 2);
  EXPECT_GT(counts.secondary_rays, 0u);
  double mean = 0, var = 0;
  for (uint8_t c : img.rgb) mean += c;
  mean /= double(img.rgb.size());
  for (uint8_t c : img.rgb) var += (c - mean) * (c - mean);
  EXPECT_GT(mean, 20.0);
  EXPECT_GT(std::sqrt(var / double(img.rgb.size())), 15.0);
  const std::string ref = std::string(ACCELBENCH_SOURCE_DIR) + "/tests/data/render_reference.png";
  if (std::getenv("ACCELBENCH_UPDATE_REFERENCE")) write_png(img, ref);
  const Image8 expected = read_png(ref);
  ASSERT_EQ(expected.width, img.width);
  ASSERT_EQ(expected.height, img.height);
  double diff = 0;
  size_t far = 0;
  for (size_t i = 0; i < img.rgb.size(); ++i) {
    const int d = std::abs(int(img.rgb[i]) - int(expected.rgb[i]));
    diff += d;
    far += d > 32;
  }
  EXPECT_LT(diff / double(img.rgb.size()), 2.0);
  EXPECT_LT(far, img.rgb.size() / 100);
}

TEST(Render, HeatmapCountsWorkAndHasAScale) {
  Fixture f;
  auto accel = f.accel("brute");
  RenderOptions o = f.options();
  const std::vector<float> nodes = render_work(*f.scene, *accel, o, HeatmapMetric::kPrims);
  ASSERT_EQ(nodes.size(), size_t(o.width) * size_t(o.height));
  // Brute force at both levels tests every instance, and every triangle of the ones it enters.
  for (float v : nodes) EXPECT_GE(v, 5.0f);
  const Image8 img = heatmap_image(nodes, o.width, o.height, "prims");
  EXPECT_GT(img.height, o.height);
  uint8_t lo[3], hi[3];
  viridis(0.0f, lo);
  viridis(1.0f, hi);
  EXPECT_NE(lo[0], hi[0]);
  const size_t bar_row = size_t(o.height + 4) * size_t(img.width) * 3;
  EXPECT_EQ(img.rgb[bar_row + 3 * 4], lo[0]);  // the bar starts at the low end of the map
}

TEST(Render, PngRoundTrip) {
  const fs::path p = fs::temp_directory_path() / ("accelbench_png_" + std::to_string(::getpid()) + ".png");
  Image8 img(5, 3);
  img.set(4, 2, 10, 20, 30);
  write_png(img, p.string());
  const Image8 back = read_png(p.string());
  EXPECT_EQ(back.rgb, img.rgb);
  fs::remove(p);
  EXPECT_THROW(read_png(p.string()), InputError);
}

}  // namespace
}  // namespace ab
