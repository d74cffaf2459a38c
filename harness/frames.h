// The per-frame figures of animated scenes in a report (docs/dynamic.md): each frame's total time and, per
// configuration and strategy, the mean frame time and the frame at which refitting stops paying.
#pragma once

#include <nlohmann/json.hpp>

namespace ab {

/// Fills, for the rows of animated scenes (those with a "frame"), each closest-hit row's frame_seconds (the
/// update plus every ray set's closest-hit median at the row's thread count on that frame) and
/// report["frame_summary"]: per scene, configuration (label:strategy) and thread count, every frame's update,
/// trace and frame seconds, the mean frame time over frames 1.. (frame 0 is every strategy's first build)
/// and, for refit, the first frame whose frame time exceeds rebuild's on the same frame (null when none
/// does).
void fill_frame_summary(nlohmann::json& report);

}  // namespace ab
