// What a report needs to be reproducible: the machine, the compiler and flags, the source commit and the
// library versions it was measured with.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace ab {

/// CPU model, logical cores, hardware threads TBB uses, ISA flags (SSE4.2, AVX, AVX2, FMA, AVX-512),
/// memory, operating system.
nlohmann::json machine_info();
/// Compiler, version, build type and flags (the ISA macros the build was compiled for included).
nlohmann::json compiler_info();
/// Git commit of the source tree (and whether it had uncommitted changes), "unknown" when not a checkout.
nlohmann::json source_info();
/// Versions of Embree, TBB, nlohmann-json, CLI11, GLM, OpenMesh and pugixml.
nlohmann::json library_versions();
/// The current UTC time in a strftime format (for example "%Y-%m-%dT%H:%M:%SZ").
std::string utc_now(const char* format);

}  // namespace ab
