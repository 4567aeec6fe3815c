// File output that never leaves a partial file behind; file names and text lines.
#pragma once

#include <string>

namespace quijibo {

// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so readers
// see either the old file or the whole new one. Throws quijibo::Error (naming the path and the
// system's reason) on failure, removing the temporary file.
void WriteFileAtomically(const std::string& path, const std::string& bytes);

// Creates the folder an output file goes in (and its parents) if missing: every command that writes
// a file does so once its inputs are validated. Throws quijibo::Error naming the path on failure.
void CreateParentFolder(const std::string& path);

// Whether `path` ends with `ext` (".ply"), ignoring case: file formats are chosen by extension.
bool HasExtension(const std::string& path, const std::string& ext);

// Whether a line of text holds nothing but whitespace.
bool IsBlank(const std::string& line);

// Reads a whole file; throws quijibo::Error naming the path when it cannot.
std::string ReadFile(const std::string& path);

}  // namespace quijibo
