// File output that never leaves a partial file behind.
#pragma once

#include <string>

namespace quijibo {

// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so readers
// see either the old file or the whole new one. Throws quijibo::Error (naming the path and the
// system's reason) on failure, removing the temporary file.
void WriteFileAtomically(const std::string& path, const std::string& bytes);

// Reads a whole file; throws quijibo::Error naming the path when it cannot.
std::string ReadFile(const std::string& path);

}  // namespace quijibo
