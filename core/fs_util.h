// Small filesystem helpers shared by all writers: atomic writes so that a
// killed run never leaves a truncated output file behind.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace dvso {

// Calls write(temp_path), then renames temp_path onto path. On exception the
// temporary file is removed and the exception propagates. temp_path is
// path's stem + kAtomicWriteTag + its extension, in the same folder.
void WriteAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// WriteAtomically for a file written through a stream: opens the temporary file (binary when
// asked), runs write(stream), then closes it and checks the close. An ofstream buffers the last few
// KB until close(), so a full disk or a file-size limit shows only there; checking before it would
// rename a truncated file into place. Errors name `path`, never the temporary file.
void WriteStreamAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

inline constexpr const char* kAtomicWriteTag = ".tmp-writing";

// True for the temporary file of a WriteAtomically that a killed process left
// behind: folder listings skip it, it is never a result.
bool IsUnfinishedAtomicWrite(const std::filesystem::path& path);

// Removes such leftovers from `dir` (not recursive; nothing when dir does not exist): a run that
// resumes in an output folder starts clean.
void RemoveUnfinishedAtomicWrites(const std::string& dir);

// Creates the directory (and parents); throws dvso::Error naming it on failure.
void EnsureDirectory(const std::string& path);

// A folder path made absolute, with "." and ".." resolved and no trailing separator, so that
// filename() is the folder's own name and parent_path() its parent for "a/drive", "a/drive/",
// "a/drive/." and "." alike.
std::filesystem::path NormalizedFolderPath(const std::string& path);

// Joins path components with '/'.
std::string JoinPath(const std::string& a, const std::string& b);

// "%06d"-style frame file name: FrameFileName(7, ".png") == "000007.png".
std::string FrameFileName(int index, const std::string& extension, int digits = 6);

// The number a frame's file name stands for: ParseFrameNumber("0000000069") == 69. Empty for a name
// that is not 1-12 decimal digits (KITTI raw uses 10, the odometry layout 6), so callers can say why.
std::optional<long long> ParseFrameNumber(const std::string& name);

}  // namespace dvso
