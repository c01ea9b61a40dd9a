#include "web_path.h"

#include <sstream>

namespace fploc::dashboard {
namespace fs = std::filesystem;

// Maps a request path to a file under `root` (canonical). Returns "" when the path is not allowed:
// any "..", NUL or backslash component, anything that resolves (symlinks included) outside root,
// hidden files, or not a regular file.
std::string resolve_web_path(const fs::path& root, const std::string& request_path) {
  if (request_path.empty() || request_path[0] != '/') return "";
  if (request_path.find('\0') != std::string::npos || request_path.find('\\') != std::string::npos) return "";
  std::string rel = request_path.substr(1);
  if (rel.empty() || rel.back() == '/') rel += "index.html";
  std::stringstream ss(rel);
  std::string part;
  while (std::getline(ss, part, '/'))
    if (part == ".." || part == "." || (!part.empty() && part[0] == '.')) return "";
  std::error_code ec;
  const fs::path full = fs::weakly_canonical(root / rel, ec);
  if (ec) return "";
  const std::string r = root.string(), f = full.string();
  if (f.size() <= r.size() || f.compare(0, r.size(), r) != 0 || f[r.size()] != '/') return "";
  if (!fs::is_regular_file(full, ec)) return "";
  return f;
}

}  // namespace fploc::dashboard
