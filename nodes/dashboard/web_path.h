#pragma once
#include <filesystem>
#include <string>

namespace fploc::dashboard {
// Maps a (decoded) request path to a file under the canonical folder `root`. Returns "" when the path
// is not allowed: any "..", "." or hidden component, NUL or backslash, anything resolving (symlinks
// included) outside root, or not a regular file. "/" and "dir/" map to index.html.
std::string resolve_web_path(const std::filesystem::path& root, const std::string& request_path);
}  // namespace fploc::dashboard
