// brute force against Embree on every generator and ray kind: every disagreement must be explained
// (tie, edge, graze, t-limit); none may be unexplained.
#include "accel/registry.h"
#include "accel/trace.h"
#include "datasets/generators.h"
#include "datasets/rays.h"
#include "harness/compare.h"
#include "harness/target.h"

#include <gtest/gtest.h>

namespace ab {
namespace {

TEST(EmbreeAgreement, BruteAgreesWithEmbreeOnEveryGeneratorAndRayKind) {
  for (const auto& gen : generators()) {
    const Target target = mesh_target(std::make_shared<const Mesh>(generate_mesh(gen.name, 4000, 2, Params{})),
                                      gen.name);
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
      EXPECT_GT(a.agree, rays.size() * 9 / 10) << gen.name << " / " << kind.name;
      size_t found = 0;
      for (const Hit& h : ours) found += h.found();
      if (kind.name == "primary") {
        EXPECT_GT(found, 0u) << gen.name << ": no primary ray hits, so nothing was compared";
      }
    }
  }
}

TEST(EmbreeAdapter, QualityParameterIsCheckedAndRecorded) {
  const Target target = mesh_target(std::make_shared<const Mesh>(generate_mesh("soup", 500, 1, Params{})), "soup");
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
