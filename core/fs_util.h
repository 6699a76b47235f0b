// Small filesystem helpers shared by all writers: atomic writes so that a
// killed run never leaves a truncated output file behind.
#pragma once

#include <functional>
#include <string>

namespace dvso {

// Calls write(temp_path), then renames temp_path onto path. On exception the
// temporary file is removed and the exception propagates.
void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Creates the directory (and parents); throws dvso::Error naming it on failure.
void EnsureDirectory(const std::string& path);

// Joins path components with '/'.
std::string JoinPath(const std::string& a, const std::string& b);

// "%06d"-style frame file name: FrameFileName(7, ".png") == "000007.png".
std::string FrameFileName(int index, const std::string& extension, int digits = 6);

}  // namespace dvso
