#include "datasets/generators.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "accel/core/error.h"
#include "datasets/mesh_builder.h"
#include "datasets/random.h"

namespace ab {
namespace {

constexpr float kPi = 3.14159265358979323846f;
/// Largest accepted target (triangle ids are 32-bit; memory is the practical limit).
constexpr uint64_t kMaxTriangles = 1ull << 30;

// ---------------------------------------------------------------------------------------------
// Spheres and sphereflakes

/// Adds a UV sphere with `segments` (>= 3) vertices per ring and `rings` (>= 1) rings between the
/// poles: 2 * segments * rings triangles, outward-facing.
void add_sphere(MeshBuilder& out, const vec3& center, float radius, uint32_t segments, uint32_t rings) {
  const uint32_t north = out.vertex(center + vec3(0.0f, radius, 0.0f));
  const uint32_t first = north + 1;
  for (uint32_t r = 0; r < rings; ++r) {
    const float theta = kPi * static_cast<float>(r + 1) / static_cast<float>(rings + 1);
    for (uint32_t s = 0; s < segments; ++s) {
      const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      const vec3 d(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      out.vertex(center + radius * d);
    }
  }
  const uint32_t south = out.vertex(center - vec3(0.0f, radius, 0.0f));
  auto at = [&](uint32_t r, uint32_t s) { return first + r * segments + (s % segments); };
  for (uint32_t s = 0; s < segments; ++s) out.triangle(north, at(0, s + 1), at(0, s));
  for (uint32_t r = 0; r + 1 < rings; ++r)
    for (uint32_t s = 0; s < segments; ++s) {
      out.triangle(at(r, s), at(r, s + 1), at(r + 1, s + 1));
      out.triangle(at(r, s), at(r + 1, s + 1), at(r + 1, s));
    }
  for (uint32_t s = 0; s < segments; ++s) out.triangle(south, at(rings - 1, s), at(rings - 1, s + 1));
}

/// Adds a sphere tessellated with about `budget` triangles (at least 6; at least `budget` when
/// `at_least`, so that the last sphere of a flake never leaves the total short).
uint64_t add_sphere_budget(MeshBuilder& out, const vec3& center, float radius, double budget, bool at_least) {
  const uint32_t rings =
      static_cast<uint32_t>(std::max(1.0, std::round(std::sqrt(std::max(budget, 0.0) / 4.0))));
  const double per_ring = budget / (2.0 * rings);
  const uint32_t segments =
      static_cast<uint32_t>(std::max(3.0, at_least ? std::ceil(per_ring) : std::round(per_ring)));
  add_sphere(out, center, radius, segments, rings);
  return 2ull * segments * rings;
}

/// Number of spheres in a sphereflake of the given depth: 1 + 9 + ... + 9^depth.
uint64_t flake_spheres(int depth) {
  uint64_t n = 0, level = 1;
  for (int d = 0; d <= depth; ++d, level *= 9) n += level;
  return n;
}

/// Deepest sphereflake (at most 7) that leaves at least `per_sphere` triangles per sphere.
int auto_flake_depth(uint64_t triangles, uint64_t per_sphere) {
  int depth = 0;
  while (depth < 7 && flake_spheres(depth + 1) * per_sphere <= triangles) ++depth;
  return depth;
}

/// Sphereflake state: the triangle budget is spread evenly over the spheres still to come, so
/// rounding errors of one sphere are made up by the next.
struct Flake {
  MeshBuilder& out;
  uint64_t target;
  uint64_t spheres_left;
};

/// An orthonormal frame (t, b) around the unit axis a.
void frame(const vec3& a, vec3& t, vec3& b) {
  const vec3 helper = std::fabs(a.x) < 0.9f ? vec3(1.0f, 0.0f, 0.0f) : vec3(0.0f, 1.0f, 0.0f);
  t = glm::normalize(glm::cross(helper, a));
  b = glm::cross(a, t);
}

// Haines 1987, "A proposal for standard graphics environments" (SPD "balls"): a sphere with nine
// spheres of a third of its radius touching it, six around its equator and three above, recursively,
// each child oriented along the direction from its parent.
void add_flake(Flake& f, const vec3& center, float radius, const vec3& axis, int depth) {
  // A given depth may ask for far more spheres than the count needs (depth 7: 5.4M spheres of at
  // least 6 triangles); finish() keeps a prefix, so nothing is emitted past the target.
  if (f.out.triangles() >= f.target) return;
  const double budget = static_cast<double>(f.target - std::min(f.target, f.out.triangles())) /
                        static_cast<double>(f.spheres_left);
  add_sphere_budget(f.out, center, radius, budget, f.spheres_left == 1);
  --f.spheres_left;
  if (depth == 0) return;
  vec3 t, b;
  frame(axis, t, b);
  const float child = radius / 3.0f;
  for (int i = 0; i < 9; ++i) {
    const bool upper = i >= 6;
    const float phi = upper ? kPi / 6.0f + 2.0f * kPi * (i - 6) / 3.0f : 2.0f * kPi * i / 6.0f;
    const float elevation = upper ? 0.9f : 0.0f;
    const vec3 dir =
        std::cos(elevation) * (std::cos(phi) * t + std::sin(phi) * b) + std::sin(elevation) * axis;
    add_flake(f, center + (radius + child) * dir, child, glm::normalize(dir), depth - 1);
  }
}

/// Adds a sphereflake of about `triangles` triangles (depth < 0: chosen from the count).
void add_sphereflake(MeshBuilder& out, uint64_t triangles, int depth, const vec3& center, float radius) {
  if (depth < 0) depth = auto_flake_depth(triangles, 32);
  Flake f{out, out.triangles() + triangles, flake_spheres(depth)};
  add_flake(f, center, radius, vec3(0.0f, 1.0f, 0.0f), depth);
}

Mesh make_sphereflake(uint64_t triangles, uint64_t /*seed*/, Params& params) {
  const int depth = static_cast<int>(params.get_int("depth", -1, -1, 7));
  MeshBuilder out(triangles + 64, triangles / 2 + 64);
  add_sphereflake(out, triangles, depth, vec3(0.0f), 1.0f);
  return out.finish(triangles);
}

// ---------------------------------------------------------------------------------------------
// Terrain

/// Value noise on the integer lattice of one octave, smoothly interpolated (Perlin 1985, "An image
/// synthesizer", with hashed lattice values), in [-1, 1].
float value_noise(uint64_t seed, uint64_t octave, float x, float z) {
  const float fx = std::floor(x), fz = std::floor(z);
  const int64_t ix = static_cast<int64_t>(fx), iz = static_cast<int64_t>(fz);
  auto lattice = [&](int64_t i, int64_t k) {
    const uint64_t h =
        hash_seed(seed, octave, static_cast<uint64_t>(i) * 0x100000001B3ull ^ static_cast<uint64_t>(k));
    return static_cast<float>(h >> 40) * 0x1p-23f - 1.0f;
  };
  auto smooth = [](float t) { return t * t * (3.0f - 2.0f * t); };
  const float sx = smooth(x - fx), sz = smooth(z - fz);
  const float a = lattice(ix, iz) + sx * (lattice(ix + 1, iz) - lattice(ix, iz));
  const float b = lattice(ix, iz + 1) + sx * (lattice(ix + 1, iz + 1) - lattice(ix, iz + 1));
  return a + sz * (b - a);
}

// Musgrave et al. 1989, "The synthesis and rendering of eroded fractal terrains": fractional
// Brownian motion, octaves of noise at doubling frequency with amplitude scaled by the roughness
// (a stand-in for SPD "mount"'s midpoint displacement that works on any grid size).
float fbm(uint64_t seed, float x, float z, int octaves, float roughness) {
  float sum = 0.0f, amplitude = 1.0f, frequency = 4.0f;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * value_noise(seed, static_cast<uint64_t>(o), x * frequency, z * frequency);
    amplitude *= roughness;
    frequency *= 2.0f;
  }
  return sum;
}

Mesh make_terrain(uint64_t triangles, uint64_t seed, Params& params) {
  const float roughness = static_cast<float>(params.get_float("roughness", 0.5, 0.0, 1.0));
  const float height = static_cast<float>(params.get_float("height", 0.25, 0.0, 100.0));
  const uint32_t cells = static_cast<uint32_t>(std::max(1.0, std::ceil(std::sqrt(triangles / 2.0))));
  const uint32_t side = cells + 1;
  const int octaves = std::clamp(static_cast<int>(std::ceil(std::log2(static_cast<double>(cells)))), 1, 16);
  Mesh grid;
  grid.vertices.resize(static_cast<size_t>(side) * side);
  tbb::parallel_for(uint32_t{0}, side, [&](uint32_t j) {
    for (uint32_t i = 0; i < side; ++i) {
      const float x = static_cast<float>(i) / static_cast<float>(cells);
      const float z = static_cast<float>(j) / static_cast<float>(cells);
      grid.vertices[static_cast<size_t>(j) * side + i] = {x, height * fbm(seed, x, z, octaves, roughness), z};
    }
  });
  const uint64_t rows = std::min<uint64_t>(cells, (triangles + 2ull * cells - 1) / (2ull * cells));
  grid.triangles.reserve(rows * 2 * cells);
  for (uint32_t j = 0; j < rows; ++j)
    for (uint32_t i = 0; i < cells; ++i) {
      const uint32_t a = j * side + i, b = a + 1, c = a + side, d = c + 1;
      grid.triangles.emplace_back(a, c, d);
      grid.triangles.emplace_back(a, d, b);
    }
  if (grid.triangles.size() > triangles) grid.triangles.resize(triangles);
  grid.vertices.resize(std::min<size_t>(grid.vertices.size(), static_cast<size_t>(rows + 1) * side));
  return grid;
}

// ---------------------------------------------------------------------------------------------
// Tetra

/// Sierpinski tetrahedron state: where leaves go and how many of them are refined once more.
struct Tetra {
  MeshBuilder& out;
  uint64_t target;  ///< triangles wanted: finish() keeps a prefix, so nothing is emitted past it
  uint64_t refine;  ///< leaves (in emission order) that are subdivided once more
  uint64_t leaf = 0;
};

/// Adds the four faces of tetrahedron (a, b, c, d), outward-facing for a positively oriented one.
void add_tetrahedron(MeshBuilder& out, const vec3& a, const vec3& b, const vec3& c, const vec3& d) {
  const uint32_t i = out.vertex(a);
  out.vertex(b);
  out.vertex(c);
  out.vertex(d);
  out.triangle(i, i + 2, i + 1);
  out.triangle(i, i + 1, i + 3);
  out.triangle(i + 1, i + 2, i + 3);
  out.triangle(i, i + 3, i + 2);
}

/// The four half-size corner tetrahedra of (a, b, c, d).
void split_tetrahedron(const vec3& a, const vec3& b, const vec3& c, const vec3& d, vec3 (&child)[4][4]) {
  const vec3 ab = 0.5f * (a + b), ac = 0.5f * (a + c), ad = 0.5f * (a + d);
  const vec3 bc = 0.5f * (b + c), bd = 0.5f * (b + d), cd = 0.5f * (c + d);
  const vec3 result[4][4] = {{a, ab, ac, ad}, {ab, b, bc, bd}, {ac, bc, c, cd}, {ad, bd, cd, d}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) child[i][j] = result[i][j];
}

// Haines 1987 (SPD "tetra"): the Sierpinski tetrahedron, each tetrahedron replaced by the four
// half-size tetrahedra at its corners. The first `refine` leaves go one level deeper so the count
// can fall between powers of four.
void add_tetra(Tetra& t, const vec3& a, const vec3& b, const vec3& c, const vec3& d, int depth) {
  vec3 child[4][4];
  if (t.out.triangles() >= t.target) return;
  if (depth == 0 && t.leaf++ >= t.refine) {
    add_tetrahedron(t.out, a, b, c, d);
    return;
  }
  split_tetrahedron(a, b, c, d, child);
  for (const auto& k : child) {
    if (depth == 0)
      add_tetrahedron(t.out, k[0], k[1], k[2], k[3]);
    else
      add_tetra(t, k[0], k[1], k[2], k[3], depth - 1);
  }
}

Mesh make_tetra(uint64_t triangles, uint64_t /*seed*/, Params& params) {
  const int given = static_cast<int>(params.get_int("depth", -1, -1, 13));
  int depth = given;
  if (depth < 0) {
    depth = 0;
    while (depth < 13 && (4ull << (2 * (depth + 1))) <= triangles) ++depth;
  }
  const uint64_t base = 4ull << (2 * depth);
  const uint64_t refine = given < 0 && triangles > base ? (triangles - base + 11) / 12 : 0;
  const uint64_t reserve = std::min(triangles, base + 12 * refine);
  MeshBuilder out(reserve, reserve);
  Tetra t{out, triangles, refine};
  add_tetra(t, vec3(1, 1, 1), vec3(-1, -1, 1), vec3(-1, 1, -1), vec3(1, -1, -1), depth);
  return out.finish(triangles);
}

// ---------------------------------------------------------------------------------------------
// Soup and slivers

Mesh make_soup(uint64_t triangles, uint64_t seed, Params& params) {
  const double auto_size =
      std::min(0.1, 1.5 / std::cbrt(static_cast<double>(std::max<uint64_t>(triangles, 1))));
  const float size = static_cast<float>(params.get_float("size", auto_size, 0.0, 10.0));
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 1);
  for (uint64_t i = 0; i < triangles; ++i) {
    const vec3 c = rng.unit_cube();
    const vec3 a = c + size * (rng.unit_cube() - 0.5f);
    const vec3 b = c + size * (rng.unit_cube() - 0.5f);
    out.triangle(a, b, c + size * (rng.unit_cube() - 0.5f));
  }
  return out.finish(triangles);
}

Mesh make_slivers(uint64_t triangles, uint64_t seed, Params& params) {
  const float length = static_cast<float>(params.get_float("length", 0.3, 0.0, 100.0));
  // Default aspect (length / width): the total area stays near 1.5 (about one layer over the unit
  // cube) whatever the count, with slivers at least 20 times longer than wide.
  const double auto_aspect = std::max(20.0, static_cast<double>(triangles) * length * length / 3.0);
  const float aspect = static_cast<float>(params.get_float("aspect", auto_aspect, 1.0, 1e9));
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 2);
  for (uint64_t i = 0; i < triangles; ++i) {
    const vec3 c = rng.unit_cube();
    const vec3 axis = rng.unit_sphere();
    vec3 t, b;
    frame(axis, t, b);
    const float angle = 2.0f * kPi * rng.uniform();
    const vec3 side = std::cos(angle) * t + std::sin(angle) * b;
    const vec3 half = 0.5f * length * axis;
    out.triangle(c - half, c + half, c + (length / aspect) * side + rng.uniform(-0.5f, 0.5f) * half);
  }
  return out.finish(triangles);
}

// ---------------------------------------------------------------------------------------------
// Stadium

/// Adds an open-air stadium (10 triangles): a floor from lo to hi (y = lo.y) and four walls of
/// height hi.y - lo.y, open at the top so that a camera above it sees the floor and what stands on it.
void add_stadium_bowl(MeshBuilder& out, const vec3& lo, const vec3& hi) {
  uint32_t v[8];
  for (int i = 0; i < 8; ++i)
    v[i] = out.vertex({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const int faces[5][4] = {{0, 1, 5, 4}, {0, 4, 6, 2}, {1, 3, 7, 5}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    out.triangle(v[f[0]], v[f[1]], v[f[2]]);
    out.triangle(v[f[0]], v[f[2]], v[f[3]]);
  }
}

Mesh make_stadium(uint64_t triangles, uint64_t /*seed*/, Params& params) {
  const float scale = static_cast<float>(params.get_float("scale", 100.0, 1.0, 1e6));
  const int depth = static_cast<int>(params.get_int("depth", -1, -1, 7));
  MeshBuilder out(triangles + 64, triangles / 2 + 64);
  const float half = 0.5f * scale;
  add_stadium_bowl(out, vec3(-half, 0.0f, -half), vec3(half, 0.05f * scale, half));
  if (triangles > out.triangles())
    add_sphereflake(out, triangles - out.triangles(), depth, vec3(0, 1, 0), 1.0f);
  return out.finish(triangles);
}

// ---------------------------------------------------------------------------------------------
// Cityscape

/// Adds an axis-aligned box without a bottom (10 triangles); with `duplicate_roof` the two roof
/// triangles are emitted twice (exact duplicates), with `degenerate` two zero-area triangles follow
/// (a repeated vertex, and three collinear vertices along a roof edge).
void add_building(MeshBuilder& out, const vec3& lo, const vec3& hi, bool duplicate_roof, bool degenerate) {
  uint32_t v[8];
  for (int i = 0; i < 8; ++i)
    v[i] = out.vertex({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const int sides[5][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 2, 3, 1}, {4, 5, 7, 6}, {2, 6, 7, 3}};
  for (const auto& f : sides) {
    out.triangle(v[f[0]], v[f[1]], v[f[2]]);
    out.triangle(v[f[0]], v[f[2]], v[f[3]]);
  }
  if (duplicate_roof) {
    out.triangle(v[2], v[6], v[7]);
    out.triangle(v[2], v[7], v[3]);
  }
  if (degenerate) {
    out.triangle(v[2], v[2], v[7]);
    const uint32_t mid = out.vertex({0.5f * (lo.x + hi.x), hi.y, lo.z});
    out.triangle(v[2], mid, v[3]);
  }
}

Mesh make_cityscape(uint64_t triangles, uint64_t seed, Params& params) {
  const int max_height = static_cast<int>(params.get_int("height", 24, 1, 100000));
  const bool degenerate = params.get_bool("degenerate", true);
  const uint32_t lots = static_cast<uint32_t>(std::max(1.0, std::ceil(std::sqrt(triangles / 9.5))));
  const float extent = 4.0f * static_cast<float>(lots);
  MeshBuilder out(triangles + 16, triangles + 16);
  const uint32_t g0 = out.vertex({-4.0f, 0.0f, -4.0f}), g1 = out.vertex({extent + 4.0f, 0.0f, -4.0f});
  const uint32_t g2 = out.vertex({-4.0f, 0.0f, extent + 4.0f}),
                 g3 = out.vertex({extent + 4.0f, 0.0f, extent + 4.0f});
  out.triangle(g0, g2, g3);
  out.triangle(g0, g3, g1);
  Rng rng(seed, 3);
  // Lots on a pitch of 4 lattice units; footprints and heights are integers, so faces of
  // neighbouring buildings are coplanar or touch and every face lies on a likely split plane.
  for (uint64_t k = 0; out.triangles() < triangles && k < uint64_t{lots} * lots; ++k) {
    const float x0 = 4.0f * static_cast<float>(k % lots) + static_cast<float>(rng.below(2));
    const float z0 = 4.0f * static_cast<float>(k / lots) + static_cast<float>(rng.below(2));
    const float w = 1.0f + static_cast<float>(rng.below(3)), d = 1.0f + static_cast<float>(rng.below(3));
    const uint64_t tall = rng.below(static_cast<uint64_t>(max_height));
    const uint64_t h = 1 + tall * rng.below(4) / 3;
    add_building(out, {x0, 0.0f, z0},
                 {std::min(x0 + w, 4.0f * (k % lots) + 4.0f), static_cast<float>(h),
                  std::min(z0 + d, 4.0f * (k / lots) + 4.0f)},
                 k % 37 == 0, degenerate && k % 50 == 0);
  }
  return out.finish(triangles);
}

// ---------------------------------------------------------------------------------------------
// Hostile inputs (issue 11): shapes unlike the scanned and procedural scenes above, which stress the
// termination rules of the space-partitioning trees.

/// Large overlapping triangles: every vertex uniform in a cube of side `size` (CAD or architectural
/// polygons, where every triangle crosses most of the scene).
Mesh make_large(uint64_t triangles, uint64_t seed, Params& params) {
  const float size = static_cast<float>(params.get_float("size", 1.0, 1e-6, 1e6));
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 20);
  for (uint64_t i = 0; i < triangles; ++i)
    out.triangle(size * rng.unit_cube(), size * rng.unit_cube(), size * rng.unit_cube());
  return out.finish(triangles);
}

/// A fan: every triangle shares one vertex (the centre of the unit cube); the other two lie at random
/// directions at distance up to `radius`, so all of them meet in one point.
Mesh make_fan(uint64_t triangles, uint64_t seed, Params& params) {
  const float radius = static_cast<float>(params.get_float("radius", 0.5, 1e-6, 1e6));
  MeshBuilder out(triangles, 2 * triangles + 1);
  Rng rng(seed, 21);
  const vec3 apex(0.5f);
  const uint32_t a = triangles ? out.vertex(apex) : 0;
  for (uint64_t i = 0; i < triangles; ++i) {
    const uint32_t b = out.vertex(apex + radius * rng.uniform() * rng.unit_sphere());
    const uint32_t c = out.vertex(apex + radius * rng.uniform() * rng.unit_sphere());
    out.triangle(a, b, c);
  }
  return out.finish(triangles);
}

/// Needles: triangles `length` long and `length / aspect` wide at random positions and directions.
Mesh make_needles(uint64_t triangles, uint64_t seed, Params& params) {
  const float length = static_cast<float>(params.get_float("length", 0.5, 1e-6, 1e6));
  const float aspect = static_cast<float>(params.get_float("aspect", 1e4, 1.0, 1e9));
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 22);
  for (uint64_t i = 0; i < triangles; ++i) {
    const vec3 c = rng.unit_cube();
    const vec3 axis = rng.unit_sphere();
    vec3 t, b;
    frame(axis, t, b);
    const vec3 half = 0.5f * length * axis;
    out.triangle(c - half, c + half, c + (length / aspect) * t);
  }
  return out.finish(triangles);
}

/// Stacks of coplanar overlapping triangles: `layers` planes z = const across the unit cube, each
/// holding its share of triangles of side about `size` at random positions, overlapping each other.
Mesh make_coplanar(uint64_t triangles, uint64_t seed, Params& params) {
  const uint64_t layers = static_cast<uint64_t>(params.get_int("layers", 4, 1, 1 << 20));
  const float size = static_cast<float>(params.get_float("size", 0.5, 1e-6, 1e6));
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 23);
  for (uint64_t i = 0; i < triangles; ++i) {
    const float z = static_cast<float>(i % layers + 1) / static_cast<float>(layers + 1);
    const vec3 c(rng.uniform(), rng.uniform(), z);
    const auto corner = [&] {
      return c + size * vec3(rng.uniform(-0.5f, 0.5f), rng.uniform(-0.5f, 0.5f), 0.0f);
    };
    const vec3 p = corner(), q = corner();
    out.triangle(p, q, corner());
  }
  return out.finish(triangles);
}

/// Geometry far from the origin: a soup of small triangles in a cube of side `extent` whose corner is
/// at (offset, offset, offset), so coordinates are near 1e6 and a float's spacing there (1/16) matters.
Mesh make_far(uint64_t triangles, uint64_t seed, Params& params) {
  const float offset = static_cast<float>(params.get_float("offset", 1e6, -1e30, 1e30));
  const float extent = static_cast<float>(params.get_float("extent", 1000.0, 1e-6, 1e30));
  const double auto_size =
      std::min(0.1, 1.5 / std::cbrt(static_cast<double>(std::max<uint64_t>(triangles, 1))));
  const float size = extent * static_cast<float>(auto_size);
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 24);
  for (uint64_t i = 0; i < triangles; ++i) {
    const vec3 c = vec3(offset) + extent * rng.unit_cube();
    const vec3 a = c + size * (rng.unit_cube() - 0.5f);
    const vec3 b = c + size * (rng.unit_cube() - 0.5f);
    out.triangle(a, b, c + size * (rng.unit_cube() - 0.5f));
  }
  return out.finish(triangles);
}

/// Degenerate and normal triangles mixed (the first row of issue 11): a share `large` of large random
/// triangles across the unit cube, the rest zero-area ones (a point, or three collinear vertices),
/// interleaved.
Mesh make_mixed(uint64_t triangles, uint64_t seed, Params& params) {
  const double large = params.get_float("large", 0.25, 0.0, 1.0);
  MeshBuilder out(triangles, 3 * triangles);
  Rng rng(seed, 25);
  uint64_t normal = 0;
  for (uint64_t i = 0; i < triangles; ++i) {
    const vec3 a = rng.unit_cube(), b = rng.unit_cube();
    if (static_cast<double>(normal) < large * static_cast<double>(i + 1)) {
      ++normal;
      out.triangle(a, b, rng.unit_cube());
    } else if (i % 2) {
      out.triangle(a, a, a);
    } else {
      out.triangle(a, b, a + rng.uniform() * (b - a));
    }
  }
  return out.finish(triangles);
}

}  // namespace

const std::vector<GeneratorInfo>& generators() {
  static const std::vector<GeneratorInfo> list = {
      {"sphereflake", "Haines' SPD balls: recursive spheres, each tessellated (params depth)",
       make_sphereflake},
      {"terrain", "fractal heightfield, fBm noise over a grid, SPD mount (params roughness, height)",
       make_terrain},
      {"tetra", "SPD tetra: recursive Sierpinski tetrahedra (params depth)", make_tetra},
      {"soup", "uniformly random small triangles in the unit cube (params size)", make_soup},
      {"stadium",
       "teapot in a stadium: a dense sphereflake in the middle of a huge open-air stadium (params scale, "
       "depth)",
       make_stadium},
      {"slivers", "long thin triangles at random angles (params length, aspect)", make_slivers},
      {"cityscape",
       "axis-aligned boxes on an integer lattice over a ground plane, with duplicate and zero-area triangles "
       "(params height, degenerate)",
       make_cityscape},
      {"large", "large overlapping triangles: every vertex uniform in the cube (params size)", make_large},
      {"fan", "a fan: every triangle shares the cube's centre as a vertex (params radius)", make_fan},
      {"needles", "needles: long triangles of a tiny width at random angles (params length, aspect)",
       make_needles},
      {"coplanar", "stacks of coplanar overlapping triangles in planes z = const (params layers, size)",
       make_coplanar},
      {"far", "small random triangles in a cube far from the origin, near 1e6 (params offset, extent)",
       make_far},
      {"mixed",
       "large random triangles across the cube mixed with zero-area and collinear ones (params large)",
       make_mixed},
  };
  return list;
}

Mesh generate_mesh(const std::string& name, uint64_t triangles, uint64_t seed, Params params) {
  for (const GeneratorInfo& g : generators()) {
    if (g.name != name) continue;
    if (triangles > kMaxTriangles)
      throw InputError("generator '" + name + "': " + std::to_string(triangles) +
                       " triangles is more than the limit " + std::to_string(kMaxTriangles));
    // A dry run on zero triangles rejects unknown or bad parameters before the real (maybe long) run.
    Params probe = params;
    g.make(0, seed, probe);
    probe.finish("generator '" + name + "'");
    if (triangles == 0) return Mesh{};
    return g.make(triangles, seed, params);
  }
  std::string known;
  for (const GeneratorInfo& g : generators()) known += (known.empty() ? "" : ", ") + g.name;
  throw InputError("unknown generator '" + name + "' (known: " + known + ")");
}

}  // namespace ab
