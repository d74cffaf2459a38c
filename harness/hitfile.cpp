#include "harness/hitfile.h"

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <fstream>

#include "accel/core/error.h"
#include "datasets/atomic_file.h"

namespace ab {

static_assert(std::endian::native == std::endian::little, "the file formats are little-endian");

namespace {

template <class Record>
std::vector<Record> read_records(const std::string& path, const char (&magic)[9]) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  char head[8];
  if (!in.read(head, 8)) throw InputError(path + ": file too short for the magic number");
  if (std::memcmp(head, magic, 8) != 0) throw InputError(path + ": wrong magic (expected " + magic + ")");
  uint64_t count = 0;
  if (!in.read(reinterpret_cast<char*>(&count), 8))
    throw InputError(path + ": file too short for the record count");
  in.seekg(0, std::ios::end);
  const uint64_t size = static_cast<uint64_t>(in.tellg());
  const uint64_t body = size - 16;
  const uint64_t held = body / sizeof(Record);
  if (count > held)
    throw InputError(path + ": truncated: the header says " + std::to_string(count) +
                     " records but the file holds " + std::to_string(held));
  if (body != count * sizeof(Record))
    throw InputError(path + ": " + std::to_string(body - count * sizeof(Record)) + " trailing bytes after " +
                     std::to_string(count) + " records");
  std::vector<Record> records(count);
  in.seekg(16);
  if (count && !in.read(reinterpret_cast<char*>(records.data()), static_cast<std::streamsize>(body)))
    throw InputError(path + ": read failed");
  return records;
}

template <class Record>
void write_records(const std::string& path, const char (&magic)[9], const std::vector<Record>& records) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(magic, 8);
    const uint64_t count = records.size();
    out.write(reinterpret_cast<const char*>(&count), 8);
    out.write(reinterpret_cast<const char*>(records.data()),
              static_cast<std::streamsize>(count * sizeof(Record)));
  });
}

/// An ABRAYS01 record: a Ray without its time (the first 32 bytes of the ABRAYS02 record).
struct RayRecordV1 {
  float values[8];
};
static_assert(sizeof(RayRecordV1) == 32 && offsetof(Ray, time) == sizeof(RayRecordV1));

/// The version a .rays file's magic names: ABRAYS02 is version 2, anything else is read as version 1
/// (whose reader names a wrong magic).
RayFileVersion ray_file_version(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  if (in.read(head, 8) && std::memcmp(head, "ABRAYS02", 8) == 0) return RayFileVersion::kV2;
  return RayFileVersion::kV1;
}

bool finite3(const vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

std::vector<Ray> read_rays(const std::string& path) {
  std::vector<Ray> rays;
  if (ray_file_version(path) == RayFileVersion::kV1) {
    const std::vector<RayRecordV1> v1 = read_records<RayRecordV1>(path, "ABRAYS01");
    rays.resize(v1.size());
    for (size_t i = 0; i < v1.size(); ++i) {
      const float* f = v1[i].values;
      rays[i] = Ray{vec3(f[0], f[1], f[2]), vec3(f[3], f[4], f[5]), f[6], f[7], 0.0f};
    }
  } else {
    rays = read_records<Ray>(path, "ABRAYS02");
  }
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    if (!finite3(r.org) || !finite3(r.dir) || !std::isfinite(r.tmin) || !(r.tmax > -kInf))
      throw InputError(path + ": ray " + std::to_string(i) +
                       " has a NaN or infinite value (only tmax may be +inf)");
    if (!(r.time >= 0.0f && r.time <= 1.0f))
      throw InputError(path + ": ray " + std::to_string(i) + " has time " + std::to_string(r.time) +
                       " (NaN or outside [0, 1])");
  }
  return rays;
}

void write_rays(const std::string& path, const std::vector<Ray>& rays, RayFileVersion version) {
  if (version == RayFileVersion::kV2) return write_records(path, "ABRAYS02", rays);
  std::vector<RayRecordV1> v1(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) std::memcpy(&v1[i], &rays[i], sizeof(RayRecordV1));
  write_records(path, "ABRAYS01", v1);
}

size_t ray_record_bytes(const std::string& path) {
  return ray_file_version(path) == RayFileVersion::kV2 ? sizeof(Ray) : sizeof(RayRecordV1);
}

std::vector<Hit> read_hits(const std::string& path) {
  return read_records<Hit>(path, "ABHITS01");
}

void write_hits(const std::string& path, const std::vector<Hit>& hits) {
  write_records(path, "ABHITS01", hits);
}

}  // namespace ab
