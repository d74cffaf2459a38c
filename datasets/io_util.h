// Small helpers shared by the mesh readers and writers: exact binary reads, little-endian
// output, and strict number parsing with the file and line in the error.
#pragma once

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <istream>
#include <limits>
#include <string>
#include <string_view>

#include "accel/core/error.h"

namespace ab {

static_assert(std::endian::native == std::endian::little, "binary mesh I/O assumes a little-endian host");

/// Size of a file in bytes.
inline uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read file size: " + ec.message());
  return size;
}

/// Reads exactly n bytes or throws naming the file.
inline void read_exactly(std::istream& in, char* data, size_t n, const std::string& path) {
  in.read(data, static_cast<std::streamsize>(n));
  if (static_cast<size_t>(in.gcount()) != n) throw InputError(path + ": unexpected end of file");
}

/// Appends a little-endian 32-bit value.
template <class T>
inline void put_le32(std::string& buffer, T value) {
  static_assert(sizeof(T) == 4);
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  for (int i = 0; i < 4; ++i) buffer.push_back(static_cast<char>((bits >> (8 * i)) & 0xFF));
}

/// Parses a whole token as a float (from_chars: locale-independent, accepts nan/inf, which the
/// callers reject separately), or throws naming the file and line. A number beyond the float range is
/// refused as such; one below it (1e-50) rounds to zero or a denormal, as the text's nearest float.
inline float parse_float(std::string_view token, const std::string& path, size_t line) {
  float f = 0.0f;
  const char* last = token.data() + token.size();
  const auto [end, ec] = std::from_chars(token.data(), last, f);
  auto refuse = [&](const char* why) {
    return InputError(path + ":" + std::to_string(line) + ": '" + std::string(token) + "' " + why);
  };
  if (token.empty() || end != last || (ec != std::errc() && ec != std::errc::result_out_of_range))
    throw refuse("is not a number");
  if (ec == std::errc()) return f;
  // Out of the float range (from_chars leaves f): the nearest double (strtod, the program's "C" locale,
  // on text from_chars accepted) tells too large from too small.
  const double d = std::strtod(std::string(token).c_str(), nullptr);
  if (std::abs(d) <= double(std::numeric_limits<float>::max())) return float(d);
  throw refuse("is beyond the range of a 32-bit float");
}

/// Splits off the next whitespace-separated token of `rest` ("" at the end).
inline std::string_view next_token(std::string_view& rest) {
  const size_t start = rest.find_first_not_of(" \t\r");
  if (start == std::string_view::npos) {
    rest = {};
    return {};
  }
  const size_t end = rest.find_first_of(" \t\r", start);
  const std::string_view token =
      rest.substr(start, end == std::string_view::npos ? rest.size() - start : end - start);
  rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end);
  return token;
}

}  // namespace ab
