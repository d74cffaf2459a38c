#include "harness/options.h"

#include <charconv>

#include "accel/core/error.h"
#include "harness/cli.h"
#include "tracer/scene.h"

namespace ab {

namespace {
/// A decimal integer spanning all of s.
bool parse_count(const std::string& s, uint64_t& v) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && ptr == s.data() + s.size();
}
}  // namespace

void FrameOptions::add(CLI::App& app) {
  auto* t = app.add_option("--time", time, "animated scenes: normalized time in [0, 1]")
                ->check(CLI::Range(0.0, 1.0));
  auto* f = app.add_option("--frame", frame, "animated scenes: frame F of --frames N")
                ->check(CLI::NonNegativeNumber);
  auto* n = app.add_option("--frames", frames, "animated scenes: the frame count N of --frame");
  t->excludes(f);
  t->excludes(n);
}

bool FrameOptions::range(uint64_t& first, uint64_t& last) const {
  const size_t dash = frames.find('-');
  if (dash == std::string::npos) return false;
  if (!parse_count(frames.substr(0, dash), first) || !parse_count(frames.substr(dash + 1), last) ||
      last < first)
    throw InputError("--frames " + frames + ": expected a count N or a range A-B with A <= B");
  return true;
}

float FrameOptions::normalized_time(bool allow_range) const {
  if (time >= 0.0) return float(time);
  uint64_t first = 0, last = 0;
  if (!frames.empty() && range(first, last)) {
    if (!allow_range)
      throw InputError("--frames " + frames + ": expected a frame count N (a range is for render)");
    if (frame >= 0) throw InputError("--frame F goes with --frames N, not with a range");
    return 0.0f;
  }
  uint64_t count = 0;
  if (!frames.empty() && !parse_count(frames, count))
    throw InputError("--frames " + frames + ": expected a frame count N (at least 1)");
  if (frame >= 0 && frames.empty()) throw InputError("--frame F needs --frames N");
  if (frames.empty()) return 0.0f;
  if (frame < 0) throw InputError("--frames N needs --frame F");
  return frame_time(uint64_t(frame), count);
}

void TargetOptions::add(CLI::App& app) {
  auto* m = app.add_option("--mesh", mesh, "mesh file (.obj, .ply, .off, .stl)")->check(CLI::ExistingFile);
  auto* s = app.add_option("--scene", scene, "scene file (.xml, .gltf, .glb)")->check(CLI::ExistingFile);
  frame.add(app);
  m->excludes(s);
  s->excludes(m);
  app.callback([&app, this] {
    if (mesh.empty() && scene.empty()) throw CLI::RequiredError("--mesh or --scene");
    (void)app;
  });
}

void StructureOptions::add(CLI::App& app) {
  app.add_option("--accel-top", top, "scenes: top-level accelerator")->check(accelerator_name_validator());
  app.add_option("--accel-bottom", bottom, "scenes: per-mesh accelerator")
      ->check(accelerator_name_validator());
  app.add_option("--param", params, "accelerator parameter k=v (repeatable)");
}

void add_threads_option(CLI::App& app, int& threads) {
  app.add_option("--threads", threads, "threads (0: all cores)")->check(CLI::Range(0, 1024));
}

Params params_from(const std::vector<std::string>& kvs) {
  Params p;
  for (const auto& kv : kvs) p.add(kv);
  return p;
}

}  // namespace ab
