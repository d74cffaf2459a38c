// Writing an output file whole or not at all: to a temporary name beside it, renamed when complete.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace ab {

/// Calls write(stream) on a temporary file next to path and renames it to path when write returns
/// and the stream is good. On any exception or stream failure the temporary file is removed, path
/// is left untouched, and an InputError naming path is thrown (or the exception is rethrown).
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = true);

}  // namespace ab
