#include "harness/machine.h"

#include <OpenMesh/Core/System/config.h>
#include <embree3/rtcore_config.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/version.h>
#include <sys/utsname.h>

#include <CLI/Version.hpp>
#include <array>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <pugixml.hpp>
#include <set>
#include <sstream>
#include <string>
#include <thread>

namespace ab {

namespace {

/// The value of the first "key : value" line of a /proc file whose key is `key`.
std::string proc_field(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string k = line.substr(0, colon);
    while (!k.empty() && (k.back() == ' ' || k.back() == '\t')) k.pop_back();
    if (k != key) continue;
    std::string v = line.substr(colon + 1);
    const auto start = v.find_first_not_of(" \t");
    return start == std::string::npos ? "" : v.substr(start);
  }
  return "";
}

/// Runs a shell command and returns its first line of output ("" on failure).
std::string command_output(const std::string& cmd) {
  FILE* pipe = ::popen((cmd + " 2>/dev/null").c_str(), "r");
  if (!pipe) return "";
  std::array<char, 512> buf{};
  std::string out;
  if (std::fgets(buf.data(), int(buf.size()), pipe)) out = buf.data();
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

/// Version of an installed Debian package (Google Benchmark has no version macro), or "unknown".
std::string debian_version(const std::string& package) {
  const std::string v = command_output("dpkg-query -W -f='${Version}' " + package);
  return v.empty() ? "unknown" : v;
}

nlohmann::json isa_flags() {
  static const std::set<std::string> wanted{"sse4_1",  "sse4_2",   "avx",      "avx2", "fma",  "bmi2",
                                            "avx512f", "avx512vl", "avx512bw", "neon", "asimd"};
  std::string flags = proc_field("/proc/cpuinfo", "flags");
  if (flags.empty()) flags = proc_field("/proc/cpuinfo", "Features");
  std::istringstream ss(flags);
  nlohmann::json out = nlohmann::json::array();
  for (std::string f; ss >> f;)
    if (wanted.count(f)) out.push_back(f);
  return out;
}

std::string compiled_isa() {
  std::string s;
#ifdef __SSE4_2__
  s += " sse4.2";
#endif
#ifdef __AVX__
  s += " avx";
#endif
#ifdef __AVX2__
  s += " avx2";
#endif
#ifdef __FMA__
  s += " fma";
#endif
#ifdef __AVX512F__
  s += " avx512f";
#endif
  return s.empty() ? "baseline" : s.substr(1);
}

/// The flags the core library was compiled with, read from compile_commands.json in the build folder
/// (the executable's folder; CMAKE_EXPORT_COMPILE_COMMANDS is on): every argument but the compiler,
/// -o/-c and their files, -I and -D (but -DNDEBUG).
std::string build_flags() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  std::ifstream in(exe.parent_path() / "compile_commands.json");
  if (!in) return "";
  try {
    const nlohmann::json db = nlohmann::json::parse(in);
    for (const auto& entry : db) {
      if (entry.value("file", "").find("accel/core/trace.cpp") == std::string::npos) continue;
      std::istringstream args(entry.value("command", ""));
      std::string arg, flags;
      args >> arg;  // the compiler
      while (args >> arg) {
        if (arg == "-o" || arg == "-c") {
          args >> arg;
          continue;
        }
        if (arg.rfind("-I", 0) == 0 || (arg.rfind("-D", 0) == 0 && arg != "-DNDEBUG")) continue;
        flags += (flags.empty() ? "" : " ") + arg;
      }
      return flags;
    }
  } catch (const nlohmann::json::exception&) {
  }
  return "";
}

}  // namespace

nlohmann::json machine_info() {
  struct utsname u {};
  ::uname(&u);
  const std::string mem_kb = proc_field("/proc/meminfo", "MemTotal");
  std::string model = proc_field("/proc/cpuinfo", "model name");
  if (model.empty()) model = command_output("uname -p");
  return {{"cpu_model", model},
          {"logical_cores", std::thread::hardware_concurrency()},
          {"tbb_default_concurrency", tbb::info::default_concurrency()},
          {"isa_flags", isa_flags()},
          {"memory_bytes", mem_kb.empty() ? 0ull : std::stoull(mem_kb) * 1024ull},
          {"os", std::string(u.sysname) + " " + u.release},
          {"hostname", std::string(u.nodename)}};
}

nlohmann::json compiler_info() {
#if defined(__clang__)
  const std::string compiler = "clang";
#elif defined(__GNUC__)
  const std::string compiler = "gcc";
#else
  const std::string compiler = "unknown";
#endif
#ifdef NDEBUG
  const bool ndebug = true;
#else
  const bool ndebug = false;
#endif
#ifdef __OPTIMIZE__
  const bool optimized = true;
#else
  const bool optimized = false;
#endif
  std::string flags = build_flags();
  if (flags.empty()) flags = "unknown (no compile_commands.json beside the executable)";
  return {{"compiler", compiler},
          {"version", __VERSION__},
          {"cxx_standard", long(__cplusplus)},
          {"flags", flags},
          {"optimized", optimized},
          {"ndebug", ndebug},
          {"compiled_isa", compiled_isa()}};
}

nlohmann::json source_info() {
  const std::string dir = ACCELBENCH_SOURCE_DIR;
  const std::string git = "git -C '" + dir + "' ";
  std::string commit = command_output(git + "rev-parse HEAD");
  const bool dirty = !command_output(git + "status --porcelain --untracked-files=no").empty();
  if (commit.empty()) commit = "unknown";
  return {{"git_commit", commit}, {"git_dirty", dirty}, {"source_dir", dir}};
}

std::string utc_now(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

nlohmann::json library_versions() {
  auto om = [] {
    std::ostringstream s;
    s << (OM_VERSION >> 16) << "." << ((OM_VERSION >> 8) & 0xff) << "." << (OM_VERSION & 0xff);
    return s.str();
  };
  return {
      {"embree", RTC_VERSION_STRING},
      {"tbb", TBB_VERSION_STRING},
      {"tbb_runtime", TBB_runtime_version()},
      {"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                            std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                            std::to_string(NLOHMANN_JSON_VERSION_PATCH)},
      {"cli11", CLI11_VERSION},
      {"glm", std::to_string(GLM_VERSION_MAJOR) + "." + std::to_string(GLM_VERSION_MINOR) + "." +
                  std::to_string(GLM_VERSION_PATCH) + "." + std::to_string(GLM_VERSION_REVISION)},
      {"openmesh", om()},
      {"pugixml", std::to_string(PUGIXML_VERSION / 1000) + "." + std::to_string(PUGIXML_VERSION % 1000 / 10)},
      {"google_benchmark", debian_version("libbenchmark-dev")}};
}

}  // namespace ab
