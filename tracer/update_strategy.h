// Per-frame update strategies of a scene's structure (docs/dynamic.md): how a structure follows an animated
// scene from one frame to the next.
//   rebuild   every level from scratch, every frame.
//   refit     boxes recomputed over the unchanged topology (Wald, Boulos and Shirley 2007, "Ray tracing
//             deformable scenes using dynamic bounding volume hierarchies"): deforming meshes' bottom levels
//             and the top level are refitted (the BVHs; accel/bvh/refit.h).
//   adaptive  refit, and rebuild when the SAH cost has grown past `threshold` times the cost right after the
//             last rebuild (Lauterbach et al. 2006, "RT-DEFORM: interactive ray tracing of dynamic scenes
//             using BVHs"; Ize, Wald and Parker 2007, "Asynchronous BVH construction for ray tracing dynamic
//             scenes on parallel multi-core architectures"). As in Ize et al., the decision for a frame uses
//             the cost measured after the previous frame, so a frame pays one update, never two.
//   top-level the bottom levels of rigid meshes are built once; only the top level over the moving
//             instances is rebuilt every frame (Wald, Benthin and Slusallek 2003, "Distributed interactive
//             ray tracing of dynamic scenes"); a deforming mesh's bottom level is rebuilt.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "accel/core/params.h"
#include "tracer/scene.h"

namespace ab {

/// A per-frame update strategy.
enum class UpdateStrategy { kRebuild, kRefit, kAdaptive, kTopLevel };

/// Every strategy, in report order.
const std::vector<UpdateStrategy>& all_update_strategies();
/// The strategy's name in suites and reports: rebuild, refit, adaptive, top-level.
std::string strategy_name(UpdateStrategy strategy);
/// The strategy named `name`; throws ParamError naming it and the valid names.
UpdateStrategy parse_strategy(const std::string& name);

/// What one frame's update did.
struct FrameUpdate {
  double seconds = 0.0;   ///< wall time of the update alone (build, refit or rebuild)
  double sah_cost = 0.0;  ///< update_sah_cost() of the structure after it
  bool rebuilt = false;   ///< built from scratch this frame
};

/// The SAH cost a structure is compared with itself by over frames: for an 8-wide BVH the wide tree's
/// (wide_sah_cost; its binary tree is gone after a refit), otherwise sah_cost; for a two-level structure the
/// top level's plus every bottom level's. 0 when the structure computes none.
double update_sah_cost(const Accelerator& accel);

/// The structure of one animated scene kept across its frames and updated by one strategy.
class FrameUpdater {
 public:
  /// `name`: a registered structure for both levels (or embree); params as make_scene_accelerator takes
  /// them. `threshold`: adaptive rebuilds once the cost exceeds threshold x the cost after the last rebuild.
  FrameUpdater(std::string name, Params params, UpdateStrategy strategy, double threshold = 1.5);

  /// True when structure `name` can follow `strategy`: rebuild always; refit and adaptive when both of
  /// its levels refit (probed on a one-triangle scene); top-level for the project's two-level structures;
  /// Embree's own instancing refits (EmbreeSceneFrames) but has no SAH cost for adaptive.
  static bool supports(const std::string& name, const Params& params, UpdateStrategy strategy);

  /// Brings the structure to `frame` (scene_at of the same scene): the first call builds, later calls
  /// update by the strategy. Throws InputError when the frame does not match the first one's meshes.
  FrameUpdate update(std::shared_ptr<const Scene> frame);
  /// Does the last update again, to time it with repetitions as builds are (the update alone): a rebuild
  /// builds the frame again; a refit first goes back to the previous frame's positions (untimed), then
  /// refits to the frame again, the same work on the same structure. The strategy's state (costs, rebuild
  /// count) and the resulting structure are as after the update itself. Returns the seconds of the update.
  double repeat_update();
  /// The current structure (after the first update).
  const Accelerator& accelerator() const { return *accel_; }
  /// Frames rebuilt from scratch so far (the first included).
  int rebuilds() const { return rebuilds_; }

 private:
  FrameUpdate rebuild(std::shared_ptr<const Scene> frame);
  FrameUpdate refit(std::shared_ptr<const Scene> frame, bool top_only);

  std::string name_;
  Params params_;
  UpdateStrategy strategy_;
  double threshold_;
  std::unique_ptr<Accelerator> accel_;
  double rebuilt_cost_ = 0.0;  ///< cost right after the last rebuild
  double last_cost_ = 0.0;     ///< cost after the last update
  int rebuilds_ = 0;
  std::shared_ptr<const Scene> current_, previous_;  ///< the frame of the last update, and the one before
  bool last_rebuilt_ = false;                        ///< the last update built from scratch
  bool last_top_only_ = false;                       ///< the last refit kept the bottom levels
};

}  // namespace ab
