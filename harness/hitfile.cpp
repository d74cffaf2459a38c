#include "harness/hitfile.h"

#include <bit>
#include <cmath>
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

bool finite3(const vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

std::vector<Ray> read_rays(const std::string& path) {
  std::vector<Ray> rays = read_records<Ray>(path, "ABRAYS01");
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    if (!finite3(r.org) || !finite3(r.dir) || !std::isfinite(r.tmin) || std::isnan(r.tmax))
      throw InputError(path + ": ray " + std::to_string(i) + " has a NaN or infinite value");
  }
  return rays;
}

void write_rays(const std::string& path, const std::vector<Ray>& rays) {
  write_records(path, "ABRAYS01", rays);
}

std::vector<Hit> read_hits(const std::string& path) {
  return read_records<Hit>(path, "ABHITS01");
}

void write_hits(const std::string& path, const std::vector<Hit>& hits) {
  write_records(path, "ABHITS01", hits);
}

}  // namespace ab
