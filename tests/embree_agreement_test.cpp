// brute force against Embree on every generator and ray kind: every disagreement must be explained
// (tie, edge, graze, t-limit, rounding); none may be unexplained.
#include <gtest/gtest.h>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/compare.h"
#include "harness/target.h"

namespace ab {
namespace {

TEST(EmbreeAgreement, BruteAgreesWithEmbreeOnEveryGeneratorAndRayKind) {
  for (const auto& gen : generators()) {
    const Target target =
        mesh_target(std::make_shared<const Mesh>(generate_mesh(gen.name, 4000, 2, Params{})), gen.name);
    auto brute = make_target_accelerator(target, "brute", Params{});
    auto embree = make_target_accelerator(target, "embree", Params{});
    brute->build();
    embree->build();
    const RayTarget rt = ray_target(target);
    for (const auto& kind : ray_kinds()) {
      const std::vector<Ray> rays = make_rays(kind.name, rt, 2000, 9);
      std::vector<Hit> ours(rays.size()), theirs(rays.size());
      trace_closest(*brute, rays, ours, 2);
      trace_closest(*embree, rays, theirs, 2);
      const Agreement a = classify_agreement(rays, ours, theirs, hit_triangles(target));
      EXPECT_EQ(a.unexplained, 0u) << gen.name << " / " << kind.name << ": first unexplained ray "
                                   << (a.unexplained_rays.empty() ? 0 : a.unexplained_rays.front());
      // Ties count with agreement: on a stack of coplanar overlapping triangles (the coplanar generator)
      // most hits are ties by construction, where each side may name a different triangle at the same t.
      EXPECT_GT(a.agree + a.tie, rays.size() * 9 / 10) << gen.name << " / " << kind.name;
      size_t found = 0;
      for (const Hit& h : ours) found += h.found();
      if (kind.name == "primary") {
        EXPECT_GT(found, 0u) << gen.name << ": no primary ray hits, so nothing was compared";
      }
    }
  }
}

/// The agreement of each pair (ours[i], theirs[i]) of hits of the one ray.
Agreement classify_on(const Ray& ray, const std::vector<Hit>& ours, const std::vector<Hit>& theirs,
                      const HitTriangleFn& triangle_of) {
  return classify_agreement(std::vector<Ray>(ours.size(), ray), ours, theirs, triangle_of);
}

TEST(EmbreeAgreement, SliverHitsWithinRoundingOfALongEdgeAreEdgeCases) {
  // A sliver of aspect 3000 (length 0.3, height 1e-4): a hit 2e-8 from its long edge has a barycentric
  // weight of 2e-4, above the barycentric tolerance but well within float rounding at coordinates near 1.
  const Triangle sliver{{0.5f, 0.5f, 0.5f}, {0.8f, 0.5f, 0.5f}, {0.5f, 0.5001f, 0.5f}};
  const Triangle plain{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const auto triangle_of = [&](const Hit& h) { return h.prim == 0 ? sliver : plain; };
  Ray ray;
  ray.org = {0.6f, 0.5f, 0.0f};
  ray.dir = {0, 0, 1};
  const Hit miss;
  const Hit near_long_edge{0.5f, 0, 0, 0.3f, 2e-4f};  // weight of v2 (the apex above the long edge)
  const Hit inside_sliver{0.5f, 0, 0, 0.3f, 0.5f};
  const Hit inside_plain{0.5f, 1, 0, 0.3f, 0.3f};
  const Agreement a =
      classify_on(ray, {miss, miss, miss}, {near_long_edge, inside_sliver, inside_plain}, triangle_of);
  EXPECT_EQ(a.edge, 1u);
  EXPECT_EQ(a.unexplained, 2u);
  EXPECT_EQ(a.unexplained_rays, (std::vector<size_t>{1, 2}));
}

TEST(EmbreeAgreement, TheSameSliverAtTsWithinRoundingIsRoundingNotOtherwise) {
  // 200k `needles`, triangle 146525 (aspect 5000) and diffuse ray 9047 of seed 11: brute force and every
  // structure hit it at t = 0.1252377, Embree at 0.1253443 (8.5e-4 of t apart; the exact t is 0.1254431).
  const Triangle needle{{0.774531603f, 0.587504685f, 0.22915706f},
                        {0.365794897f, 0.3421565f, 0.0783639252f},
                        {0.57016325f, 0.464856744f, 0.15371789f}};
  const Triangle plain{{0.3f, 0.2f, 0.5f}, {0.9f, 0.3f, 0.4f}, {0.4f, 0.8f, 0.6f}};
  const auto triangle_of = [&](const Hit& h) { return h.prim == 0 ? needle : plain; };
  Ray ray;
  ray.org = {0.45672214f, 0.434703141f, 0.083335571f};
  ray.dir = {0.824647069f, 0.192399576f, 0.531920731f};
  ray.tmin = 2.28340323e-05f;
  const Hit ours{0.12523773f, 0, 0, 0.38644785f, 0.2768091f};
  const Hit embree{0.12534431f, 0, 0, 0.38646773f, 0.27669218f};
  const Hit far_on_needle{0.14f, 0, 0, 0.38644785f, 0.2768091f};  // 12% of t: beyond the bound
  const Hit plain_a{0.5f, 1, 0, 0.3f, 0.3f}, plain_b{0.5005f, 1, 0, 0.3f, 0.3f};  // 1e-3 on a plain one
  const Agreement a = classify_on(ray, {ours, ours, plain_a}, {embree, far_on_needle, plain_b}, triangle_of);
  EXPECT_EQ(a.rounding, 1u);
  EXPECT_EQ(a.unexplained, 2u);
  EXPECT_EQ(a.unexplained_rays, (std::vector<size_t>{1, 2}));
}

TEST(EmbreeAdapter, QualityParameterIsCheckedAndRecorded) {
  const Target target =
      mesh_target(std::make_shared<const Mesh>(generate_mesh("soup", 500, 1, Params{})), "soup");
  Params p;
  p.add("quality=high");
  auto e = make_target_accelerator(target, "embree", p);
  EXPECT_EQ(e->config()["quality"], "high");
  Params bad;
  bad.add("quality=ultra");
  EXPECT_THROW(make_target_accelerator(target, "embree", bad), ParamError);
  Params unknown;
  unknown.add("bins=4");
  EXPECT_THROW(make_target_accelerator(target, "embree", unknown), ParamError);
}

}  // namespace
}  // namespace ab
