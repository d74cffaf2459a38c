// Which registered accelerators a command means: the names it lists, what "all" stands for, the structure
// used when none is named, and comma-separated lists of names.
#pragma once

#include <set>
#include <string>
#include <vector>

namespace ab {

/// True for an accelerator registered by the tests only ("test-..."): listings and "all" leave it out.
bool is_test_only(const std::string& name);
/// True when an accelerator of that name is registered.
bool is_registered(const std::string& name);
/// The registered names a user sees, in listing order: every one but the test-only ones and `excluded`.
std::vector<std::string> listed_accelerators(const std::set<std::string>& excluded = {});
/// The structure used when none is named (ray generation, render): the project's SAH BVH where it is
/// registered (deterministic, identical to brute), else brute force.
std::string default_structure();
/// The items of a comma-separated list, in order ("a,b" -> {"a", "b"}; an empty item between two commas is
/// kept, a trailing comma adds none).
std::vector<std::string> split_list(const std::string& text);

}  // namespace ab
