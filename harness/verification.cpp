#include "harness/verification.h"

#include <algorithm>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "accel/reference/embree_device.h"
#include "harness/compare.h"
#include "harness/selection.h"

namespace ab {

using nlohmann::json;

bool is_exact(const std::string& accelerator) {
  if (accelerator == "brute" || !is_registered(accelerator)) return true;
  return !find_accelerator(accelerator).is_reference;  // embree, cgal, bullet: classified instead
}

std::unique_ptr<Accelerator> build_default(const Target& target, const std::string& name) {
  std::unique_ptr<Accelerator> accel = make_target_accelerator(target, name, Params{});
  accel->build();
  return accel;
}

std::vector<Hit> closest_hits(const Accelerator& accel, std::span<const Ray> rays, int threads) {
  std::vector<Hit> hits(rays.size());
  trace_closest(accel, rays, hits, threads);
  return hits;
}

namespace {

/// "first ray N" of a failure line.
std::string first_ray(const std::vector<uint64_t>& rays) {
  return "(first ray " + std::to_string(rays.empty() ? 0 : rays.front()) + ")";
}

/// "D of C hits differ from WHOM (first ray N)" when the comparison found differences.
bool report_differences(const IdenticalResult& r, const std::string& what, const std::string& whom,
                        const FailureSink& fail) {
  if (r.identical()) return false;
  fail(what + ": " + std::to_string(r.differing) + " of " + std::to_string(r.compared) +
       " hits differ from " + whom + " " + first_ray(r.first_differences));
  return true;
}

}  // namespace

void make_references(const Target& target, const std::string& scene, const VerifySpec& verify,
                     std::vector<RaySet>& sets, const FailureSink& fail) {
  if (sets.empty()) return;
  const auto brute = build_default(target, "brute");
  const auto reference = build_default(target, verify.reference);
  std::unique_ptr<Accelerator> embree;
  if (verify.embree && is_registered(kEmbreeName)) embree = build_default(target, kEmbreeName);
  for (RaySet& set : sets) {
    const size_t n = set.rays.size();
    set.brute_checked = verify.brute_rays == 0 ? n : std::min<uint64_t>(n, verify.brute_rays);
    set.brute = closest_hits(*brute, std::span<const Ray>(set.rays).first(set.brute_checked), 0);
    set.reference = closest_hits(*reference, set.rays, 0);
    const IdenticalResult r =
        compare_identical(set.brute, std::span<const Hit>(set.reference).first(set.brute_checked));
    if (!r.identical())
      fail(scene + " / " + set.spec->label + ": the reference " + verify.reference +
           " differs from brute on " + std::to_string(r.differing) + " of " + std::to_string(r.compared) +
           " rays " + first_ray(r.first_differences));
    if (embree) set.embree = closest_hits(*embree, set.rays, 0);
  }
}

namespace {

/// The byte-for-byte checks of an exact structure; returns whether both held.
bool verify_identical(const std::string& what, const std::string& reference, const RaySet& set,
                      const std::vector<Hit>& hits, json& v, const FailureSink& fail) {
  const IdenticalResult b = compare_identical(set.brute, std::span<const Hit>(hits).first(set.brute_checked));
  const IdenticalResult r = compare_identical(set.reference, hits);
  v.update({{"brute_rays_checked", b.compared},
            {"brute_mismatches", b.differing},
            {"reference_rays_checked", r.compared},
            {"reference_mismatches", r.differing}});
  if (!report_differences(b, what, "brute", fail)) report_differences(r, what, reference, fail);
  return b.identical() && r.identical();
}

/// The classification of the pair (ours, theirs) into the embree_* fields; returns whether every
/// disagreement is explained.
bool verify_agreement(const Target& target, const std::string& what, const RaySet& set,
                      const std::vector<Hit>& ours, const std::vector<Hit>& theirs, json& v,
                      const FailureSink& fail) {
  const Agreement a = classify_agreement(set.rays, ours, theirs, hit_triangles(target));
  v.update({{"embree_agree", a.agree},
            {"embree_tie", a.tie},
            {"embree_edge", a.edge},
            {"embree_graze", a.graze},
            {"embree_limit", a.limit},
            {"embree_rounding", a.rounding},
            {"embree_unexplained", a.unexplained}});
  if (a.unexplained == 0) return true;
  fail(what + ": " + std::to_string(a.unexplained) + " unexplained disagreements with " +
       v["classified_against"].get<std::string>() + " " + first_ray(a.unexplained_rays));
  return false;
}

}  // namespace

json verify_hits(const Target& target, const std::string& what, const std::string& accelerator,
                 const std::string& reference, const RaySet& set, const std::vector<Hit>& hits,
                 const FailureSink& fail) {
  json v = {{"verified", true}};
  const bool exact = is_exact(accelerator);
  if (exact && !verify_identical(what, reference, set, hits, v, fail)) v["verified"] = false;
  const std::vector<Hit>& theirs = exact ? set.embree : hits;
  const std::vector<Hit>& ours = exact ? hits : set.reference;
  // The embree_* counts classify the pair (this row, Embree), or for a reference (embree, cgal, bullet) the
  // pair (the verified reference structure, this row).
  v["classified_against"] = exact ? std::string(kEmbreeName) : reference;
  if (!theirs.empty() && !verify_agreement(target, what, set, ours, theirs, v, fail)) v["verified"] = false;
  return v;
}

uint64_t check_timed_hits(const std::string& what, const std::vector<Hit>& expected,
                          const std::vector<Hit>& actual, const FailureSink& fail) {
  const IdenticalResult r = compare_identical(expected, actual);
  if (!r.identical())
    fail(what + ": " + std::to_string(r.differing) + " hits of the timed pass differ from the counting pass");
  return r.differing;
}

uint64_t check_any_hits(const std::string& what, bool exact, const std::vector<uint8_t>& answers,
                        const RaySet& set, const FailureSink& fail) {
  uint64_t mismatches = 0;
  for (size_t i = 0; i < answers.size(); ++i) mismatches += (answers[i] != 0) != set.reference[i].found();
  if (exact && mismatches)
    fail(what + ": " + std::to_string(mismatches) +
         " any-hit answers differ from the reference's closest hits");
  return mismatches;
}

}  // namespace ab
