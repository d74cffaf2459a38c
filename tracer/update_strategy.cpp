#include "tracer/update_strategy.h"

#include <chrono>

#include "accel/core/error.h"
#include "accel/core/primitives.h"
#include "accel/core/registry.h"
#include "tracer/scene_accel.h"

namespace ab {

namespace {

/// The comparable SAH cost of one structure's own figures (see update_sah_cost).
double own_sah_cost(const nlohmann::json& stats) {
  const nlohmann::json& extra = stats.contains("extra") ? stats["extra"] : nlohmann::json::object();
  if (extra.contains("wide_sah_cost")) return extra["wide_sah_cost"].get<double>();
  return stats.value("sah_cost", 0.0);
}

/// A one-triangle scene with one instance (the probe of supports()).
std::shared_ptr<const Scene> probe_scene() {
  auto mesh = std::make_shared<Mesh>();
  mesh->vertices = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
  mesh->triangles = {{0u, 1u, 2u}};
  auto scene = std::make_shared<Scene>();
  SceneMesh m;
  m.name = "probe";
  m.mesh = mesh;
  m.base = mesh;
  scene->meshes.push_back(m);
  scene->instances.emplace_back();
  scene->bounds = scene->compute_world_bounds();
  return scene;
}

}  // namespace

double update_sah_cost(const Accelerator& accel) {
  const nlohmann::json stats = to_json(accel.stats());
  const nlohmann::json& extra = stats["extra"];
  if (!extra.contains("top") || !extra.contains("bottoms")) return own_sah_cost(stats);
  double cost = own_sah_cost(extra["top"]);
  for (const nlohmann::json& b : extra["bottoms"]) cost += own_sah_cost(b);
  return cost;
}

FrameUpdater::FrameUpdater(std::string name, Params params, UpdateStrategy strategy, double threshold)
    : name_(std::move(name)), params_(std::move(params)), strategy_(strategy), threshold_(threshold) {}

bool FrameUpdater::supports(const std::string& name, const Params& params, UpdateStrategy strategy) {
  if (strategy == UpdateStrategy::kRebuild) return true;
  auto scene = probe_scene();
  std::unique_ptr<Accelerator> accel;
  try {
    accel = make_scene_accelerator(scene, name, params);
  } catch (const std::exception&) {
    return false;  // not a structure of scenes (the rebuild strategy reports the error)
  }
  // Embree's own instancing follows frames by rebuilding or by its refit (it reports no SAH cost to adapt
  // by).
  if (dynamic_cast<EmbreeSceneFrames*>(accel.get())) return strategy == UpdateStrategy::kRefit;
  auto* two_level = dynamic_cast<SceneAccelerator*>(accel.get());
  if (!two_level) return false;
  if (strategy == UpdateStrategy::kTopLevel) return true;
  accel->build();
  auto moved = std::make_shared<Scene>(*scene);
  moved->meshes[0].mesh = std::make_shared<Mesh>(*scene->meshes[0].mesh);
  return two_level->update(moved, SceneAccelerator::LevelUpdate::kRefit,
                           SceneAccelerator::LevelUpdate::kRefit);
}

FrameUpdate FrameUpdater::update(std::shared_ptr<const Scene> frame) {
  previous_ = std::move(current_);
  current_ = frame;
  last_top_only_ = strategy_ == UpdateStrategy::kTopLevel;
  last_rebuilt_ = !accel_ || strategy_ == UpdateStrategy::kRebuild ||
                  (strategy_ == UpdateStrategy::kAdaptive && rebuilt_cost_ > 0.0 &&
                   last_cost_ > threshold_ * rebuilt_cost_);
  return last_rebuilt_ ? rebuild(std::move(frame)) : refit(std::move(frame), last_top_only_);
}

double FrameUpdater::repeat_update() {
  if (!accel_) throw InputError(name_ + ": no update to repeat");
  const double rebuilt_cost = rebuilt_cost_, last_cost = last_cost_;
  const int rebuilds = rebuilds_;
  double seconds = 0.0;
  if (last_rebuilt_) {
    seconds = rebuild(current_).seconds;
  } else {
    refit(previous_, last_top_only_);  // back to where the update started (refits depend on positions only)
    seconds = refit(current_, last_top_only_).seconds;
  }
  rebuilt_cost_ = rebuilt_cost, last_cost_ = last_cost, rebuilds_ = rebuilds;
  return seconds;
}

FrameUpdate FrameUpdater::rebuild(std::shared_ptr<const Scene> frame) {
  accel_ = make_scene_accelerator(std::move(frame), name_, params_);
  if (auto* embree = dynamic_cast<EmbreeSceneFrames*>(accel_.get());
      embree && strategy_ == UpdateStrategy::kRefit)
    embree->build_for_refit();
  accel_->build();
  FrameUpdate out{accel_->stats().build_seconds, update_sah_cost(*accel_), true};
  rebuilt_cost_ = last_cost_ = out.sah_cost;
  ++rebuilds_;
  return out;
}

FrameUpdate FrameUpdater::refit(std::shared_ptr<const Scene> frame, bool top_only) {
  auto* two_level = dynamic_cast<SceneAccelerator*>(accel_.get());
  auto* embree = dynamic_cast<EmbreeSceneFrames*>(accel_.get());
  using L = SceneAccelerator::LevelUpdate;
  const L level = top_only ? L::kRebuild : L::kRefit;
  bool done = false;
  if (two_level) {
    done = two_level->update(std::move(frame), level, level);
  } else if (embree && !top_only) {
    std::vector<std::shared_ptr<const Mesh>> meshes;
    std::vector<EmbreeInstanceInput> instances;
    embree_scene_inputs(*frame, meshes, instances);
    done = embree->refit_frame(meshes, instances);
  }
  if (!done) throw InputError(name_ + ": cannot follow the frame by " + strategy_name(strategy_));
  FrameUpdate out{accel_->stats().build_seconds, update_sah_cost(*accel_), false};
  last_cost_ = out.sah_cost;
  return out;
}

// SceneAccelerator::update lives here with the strategies that call it (scene_accel.cpp builds).
bool SceneAccelerator::update(std::shared_ptr<const Scene> frame, LevelUpdate bottom, LevelUpdate top) {
  if (!top_ || motion_.any() || frame->meshes.size() != scene_->meshes.size() ||
      frame->instances.size() != scene_->instances.size())
    return false;
  const auto start = std::chrono::steady_clock::now();
  for (size_t m = 0; m < bottoms_.size(); ++m) {
    if (frame->meshes[m].mesh == scene_->meshes[m].mesh) continue;  // the same geometry: kept
    if (frame->meshes[m].mesh->size() != scene_->meshes[m].mesh->size()) return false;
    if (bottom == LevelUpdate::kRefit) {
      // From the frame's indexed mesh: the refit pays for everything the traversal needs (refit.h).
      if (!bottoms_[m]->refit(frame->meshes[m].mesh)) return false;
    } else {
      bottoms_[m] = make_accelerator(bottom_name_, std::make_shared<TrianglePrims>(frame->meshes[m].mesh),
                                     bottom_params_);
      bottoms_[m]->build();
    }
  }
  scene_ = std::move(frame);
  instances_ = std::make_shared<InstancePrims>(make_instances());
  if (top == LevelUpdate::kRefit) {
    if (!top_->refit(instances_)) return false;
  } else {
    top_ = make_instance_accelerator(top_name_, instances_, top_params_);
    top_->build();
  }
  bounds_ = scene_->world_bounds();
  stats_.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  aggregate_stats();
  return true;
}

}  // namespace ab
