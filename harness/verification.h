// Verification of a suite's configurations: the reference answers of each ray set (brute force on the first
// brute_rays rays, the verified reference structure and Embree on all of them) and the checks of one
// configuration's hits against them, each failure reported as it is found.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "harness/suite.h"
#include "harness/target.h"

namespace ab {

/// A ray set of one scene with the reference answers every configuration is checked against.
struct RaySet {
  const RaySpec* spec = nullptr;  ///< the suite's ray set
  std::vector<Ray> rays;          ///< its rays on this scene
  uint64_t brute_checked = 0;     ///< the first brute_checked rays are traced by brute force
  std::vector<Hit> brute;         ///< brute force on those rays
  std::vector<Hit> reference;     ///< the verified reference structure on all rays
  std::vector<Hit> embree;        ///< Embree on all rays (empty when not compared)
};

/// Receives each failure as one line (the run marks its report failed and prints it).
using FailureSink = std::function<void(const std::string& what)>;

/// True for every structure of the project, held to brute force byte for byte; false for Embree, whose hits
/// are classified (agree, tie, edge, graze, limit, rounding) instead.
bool is_exact(const std::string& accelerator);

/// Accelerator `name` over the target with its default parameters, built.
std::unique_ptr<Accelerator> build_default(const Target& target, const std::string& name);
/// The closest hit of every ray, traced on `threads` threads (0: all).
std::vector<Hit> closest_hits(const Accelerator& accel, std::span<const Ray> rays, int threads);

/// Fills the reference answers of every set of `scene`: brute force on the first verify.brute_rays rays (0:
/// all), the reference structure on all rays (a failure where it differs from brute force), and Embree on
/// all rays when verify.embree and Embree is registered.
void make_references(const Target& target, const std::string& scene, const VerifySpec& verify,
                     std::vector<RaySet>& sets, const FailureSink& fail);

/// Checks one configuration's hits (its counting pass) on one set: byte for byte against brute force and the
/// reference when exact, classified against Embree (Embree's own hits against the reference). Returns the
/// row's verification fields: "verified" and the counts of report.csv.
nlohmann::json verify_hits(const Target& target, const std::string& what, const std::string& accelerator,
                           const std::string& reference, const RaySet& set, const std::vector<Hit>& hits,
                           const FailureSink& fail);

/// Hits of a timed pass that differ from the counting pass's (each difference a failure); returns how many.
uint64_t check_timed_hits(const std::string& what, const std::vector<Hit>& expected,
                          const std::vector<Hit>& actual, const FailureSink& fail);
/// Any-hit answers that differ from whether the reference found a closest hit; a failure when `exact`.
/// Returns how many.
uint64_t check_any_hits(const std::string& what, bool exact, const std::vector<uint8_t>& answers,
                        const RaySet& set, const FailureSink& fail);

}  // namespace ab
