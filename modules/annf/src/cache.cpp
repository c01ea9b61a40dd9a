#include "fploc/annf/cache.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "fploc/floorplan/io.h"

namespace fploc::annf {
namespace {

namespace fs = std::filesystem;

struct Fnv {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* d, size_t n) {
    const auto* p = static_cast<const unsigned char*>(d);
    for (size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  }
  template <typename T>
  void pod(const T& v) {
    bytes(&v, sizeof(T));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    bytes(s.data(), s.size());
  }
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::string describe(const AnnfOptions& o) {
  std::ostringstream s;
  s << to_string(o.mode) << ", depth " << o.max_depth;
  return s.str();
}

// The options saved with a field (index_cells is a speed setting, not saved).
bool same_saved_options(const AnnfOptions& a, const AnnfOptions& b) {
  return a.mode == b.mode && a.root_length == b.root_length && a.max_depth == b.max_depth &&
         a.paper_rule == b.paper_rule && a.exact_max_candidates == b.exact_max_candidates &&
         a.exact_refine_levels == b.exact_refine_levels && a.margin == b.margin &&
         a.paper_distinct_distances == b.paper_distinct_distances && a.paper_candidates == b.paper_candidates;
}

bool same_plan(const FloorPlan& a, const FloorPlan& b) {
  if (a.elements.size() != b.elements.size()) return false;
  auto layer = [](const FloorPlan& p, int i) { return i >= 0 && size_t(i) < p.layers.size() ? p.layers[size_t(i)] : std::string(); };
  for (size_t i = 0; i < a.elements.size(); ++i) {
    const Element &x = a.elements[i], &y = b.elements[i];
    if (x.kind != y.kind || x.a != y.a || x.b != y.b || x.c != y.c || x.r != y.r || x.a0 != y.a0 || x.a1 != y.a1 ||
        layer(a, x.layer) != layer(b, y.layer))
      return false;
  }
  return true;
}

// Loads DIR/KEY.fpmap when it holds exactly this plan and these options; nullptr otherwise.
std::shared_ptr<const Annf> try_load(const std::string& file, const FloorPlan& plan, const AnnfOptions& o) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return nullptr;
  try {
    auto a = std::make_shared<Annf>(Annf::load(file));
    if (!same_saved_options(a->options(), o) || !same_plan(a->plan(), plan)) return nullptr;
    return a;
  } catch (const std::exception&) {
    return nullptr;  // damaged or from another version: rebuilt and replaced
  }
}

// flock() on DIR/KEY.lock for the lifetime of the object (released on close, also when the process dies).
class FileLock {
 public:
  explicit FileLock(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error(path + ": " + std::strerror(errno));
    while (::flock(fd_, LOCK_EX) != 0) {
      if (errno != EINTR) {
        const int e = errno;
        ::close(fd_);
        throw std::runtime_error(path + ": flock: " + std::strerror(e));
      }
    }
  }
  ~FileLock() { ::close(fd_); }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

std::string default_annf_cache_dir() {
  if (const char* e = std::getenv("FPLOC_ANNF_CACHE"); e && *e) {
    const std::string v = e;
    if (v == "off" || v == "0" || v == "none") return "";
    return v;
  }
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/fploc/annf";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/fploc/annf";
  return "";
}

std::string annf_cache_key(const FloorPlan& plan, const AnnfOptions& o) {
  Fnv f;
  f.str("fploc-annf-cache");
  f.pod(kFpmapVersion);
  f.pod(uint64_t(plan.elements.size()));
  for (const Element& e : plan.elements) {
    f.pod(uint8_t(e.kind));
    for (double v : {e.a.x(), e.a.y(), e.b.x(), e.b.y(), e.c.x(), e.c.y(), e.r, e.a0, e.a1}) f.pod(v);
    f.str(e.layer >= 0 && size_t(e.layer) < plan.layers.size() ? plan.layers[size_t(e.layer)] : std::string());
  }
  f.pod(uint8_t(o.mode));
  f.pod(uint8_t(o.paper_rule));
  f.pod(uint8_t(o.paper_candidates));
  f.pod(uint8_t(o.paper_distinct_distances));
  f.pod(o.root_length);
  f.pod(int32_t(o.max_depth));
  f.pod(int32_t(o.exact_max_candidates));
  f.pod(int32_t(o.exact_refine_levels));
  f.pod(o.margin);
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(f.h));
  return buf;
}

std::shared_ptr<const Annf> cached_annf(const FloorPlan& plan, const AnnfOptions& options, std::string* note,
                                        const std::string& dir_in) {
  const auto t0 = std::chrono::steady_clock::now();
  auto set_note = [&](const std::string& s) {
    if (note) *note = s;
    std::cerr << "fploc annf: " << s << "\n";  // one line per field: why a start took long (or not)
  };
  auto build_only = [&](const std::string& why) {
    auto a = std::make_shared<const Annf>(Annf::build(plan, options));
    set_note("built ANNF (" + describe(options) + ") in " + std::to_string(int(ms_since(t0))) + " ms, not cached: " + why);
    return a;
  };
  const std::string dir = dir_in.empty() ? default_annf_cache_dir() : dir_in;
  if (dir.empty()) return build_only("cache off (FPLOC_ANNF_CACHE=off or no HOME)");
  if (options.index_cells != 0) return build_only("index_cells is set (speed option not stored in maps)");
  const std::string key = annf_cache_key(plan, options);
  const std::string file = dir + "/" + key + ".fpmap";
  // Fast path: no lock when the file is there (it only ever appears complete, by rename).
  if (auto a = try_load(file, plan, options)) {
    set_note("ANNF cache hit " + file + " (" + std::to_string(int(ms_since(t0))) + " ms)");
    return a;
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return build_only(dir + ": " + ec.message());
  try {
    FileLock lock(dir + "/" + key + ".lock");
    if (auto a = try_load(file, plan, options)) {  // another process built it while we waited
      set_note("ANNF cache hit " + file + " after waiting for its builder (" + std::to_string(int(ms_since(t0))) + " ms)");
      return a;
    }
    auto a = std::make_shared<const Annf>(Annf::build(plan, options));
    const double build_ms = ms_since(t0);
    std::random_device rd;
    const std::string tmp = file + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(rd());
    try {
      a->save(tmp);
      fs::rename(tmp, file);
    } catch (const std::exception& e) {
      fs::remove(tmp, ec);
      set_note("built ANNF (" + describe(options) + ") in " + std::to_string(int(build_ms)) + " ms, not cached: " + e.what());
      return a;
    }
    set_note("built ANNF (" + describe(options) + ") in " + std::to_string(int(build_ms)) + " ms, cached as " + file);
    return a;
  } catch (const std::exception& e) {
    return build_only(e.what());
  }
}

}  // namespace fploc::annf