// The ANNF block of .fpmap files (Annf::write/read) and the whole file (save/load: header and
// plan block from fploc/floorplan/io.h, then this block). Binary helpers: fploc/floorplan/binary_io.h.
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "fploc/annf/annf.h"
#include "fploc/floorplan/binary_io.h"
#include "fploc/floorplan/io.h"

namespace fploc::annf {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }
using binary::fnv1a;
using binary::get;
using binary::put;

}  // namespace

void Annf::write(std::ostream& out) const {
  put<uint8_t>(out, uint8_t(options_.mode));
  put<uint8_t>(out, uint8_t(uint8_t(options_.paper_rule) | (options_.paper_distinct_distances ? 0x80 : 0) |
                            (uint8_t(options_.paper_candidates) << 5)));
  put<double>(out, options_.root_length);
  put<int32_t>(out, options_.max_depth);
  // Low 16 bits: exact_max_candidates; high 16: exact_refine_levels (0 in maps written before it).
  put<int32_t>(out, int32_t(uint32_t(options_.exact_max_candidates) | uint32_t(options_.exact_refine_levels) << 16));
  put<double>(out, options_.margin);
  put<double>(out, origin_.x());
  put<double>(out, origin_.y());
  put<uint32_t>(out, nx_);
  put<uint32_t>(out, ny_);
  uint64_t h = 1469598103934665603ull;
  for (const auto* v : {&roots_, &nodes_, &pool_}) {
    put<uint64_t>(out, uint64_t(v->size()));
    out.write(reinterpret_cast<const char*>(v->data()), std::streamsize(v->size() * sizeof(uint32_t)));
    h = fnv1a(v->data(), v->size() * sizeof(uint32_t), h);
  }
  put<uint64_t>(out, h);
}

Annf Annf::read(std::istream& in, FloorPlan plan, const std::string& source) {
  Annf a;
  a.plan_ = std::move(plan);
  const uint8_t mode = get<uint8_t>(in, source), rule_byte = get<uint8_t>(in, source);
  const uint8_t rule = rule_byte & 0x1f, cand = (rule_byte >> 5) & 3;
  if (cand > 2) fail(source + ": corrupt map file (candidates)");
  a.options_.paper_candidates = AnnfOptions::Candidates(cand);
  if (mode > 1 || rule > 5) fail(source + ": corrupt map file (mode/rule)");
  a.options_.paper_distinct_distances = (rule_byte & 0x80) != 0;
  a.options_.mode = AnnfMode(mode);
  a.options_.paper_rule = PaperRule(rule);
  a.options_.root_length = get<double>(in, source);
  a.options_.max_depth = get<int32_t>(in, source);
  const uint32_t mc = uint32_t(get<int32_t>(in, source));
  a.options_.exact_max_candidates = int(mc & 0xffff);
  a.options_.exact_refine_levels = int(mc >> 16);
  a.options_.margin = get<double>(in, source);
  a.origin_.x() = get<double>(in, source);
  a.origin_.y() = get<double>(in, source);
  a.nx_ = get<uint32_t>(in, source);
  a.ny_ = get<uint32_t>(in, source);
  if (!(a.options_.root_length > 0) || !std::isfinite(a.options_.root_length) || a.options_.max_depth < 1 ||
      a.options_.max_depth > 20 || !a.origin_.allFinite() || a.nx_ == 0 || a.ny_ == 0 ||
      double(a.nx_) * double(a.ny_) > 5e7 || double(a.nx_) * double(1u << (a.options_.max_depth - 1)) > 2e9 ||
      double(a.ny_) * double(1u << (a.options_.max_depth - 1)) > 2e9)
    fail(source + ": corrupt map file (header values)");
  a.max_depth_ = a.options_.max_depth;
  uint64_t h = 1469598103934665603ull;
  for (auto* v : {&a.roots_, &a.nodes_, &a.pool_}) {
    const uint64_t n = get<uint64_t>(in, source);
    if (n > (1ull << 31)) fail(source + ": corrupt map file (array size)");
    v->resize(n);
    in.read(reinterpret_cast<char*>(v->data()), std::streamsize(n * sizeof(uint32_t)));
    if (!in) fail(source + ": truncated map file");
    h = fnv1a(v->data(), v->size() * sizeof(uint32_t), h);
  }
  if (get<uint64_t>(in, source) != h) fail(source + ": map file checksum mismatch (corrupt file)");
  if (a.roots_.size() != size_t(a.nx_) * a.ny_ || a.nodes_.size() % 4 != 0)
    fail(source + ": corrupt map file (tree sizes)");
  // Validate every word reachable from the roots, with a depth limit (no cycles, no bad index).
  const size_t ne = a.plan_.elements.size();
  auto check_leaf = [&](uint32_t w) {
    const uint32_t off = w & ~kLeafBit;
    if (off >= a.pool_.size() || size_t(off) + 1 + a.pool_[off] > a.pool_.size() || a.pool_[off] == 0)
      fail(source + ": corrupt map file (leaf)");
    for (uint32_t k = 0; k < a.pool_[off]; ++k)
      if (a.pool_[off + 1 + k] >= ne) fail(source + ": corrupt map file (element id)");
  };
  std::vector<std::pair<uint32_t, int>> stack;
  for (uint32_t w : a.roots_) {
    stack.push_back({w, 1});
    while (!stack.empty()) {
      auto [x, d] = stack.back();
      stack.pop_back();
      if (x & kLeafBit) {
        check_leaf(x);
        continue;
      }
      if (d >= a.max_depth_ || size_t(x) + 4 > a.nodes_.size() || x % 4 != 0)
        fail(source + ": corrupt map file (node)");
      for (int q = 0; q < 4; ++q) stack.push_back({a.nodes_[x + q], d + 1});
    }
  }
  a.prepare();
  return a;
}

void Annf::save(const std::string& path) const {
  std::ofstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot write (" + std::strerror(errno) + ")");
  f.write(kFpmapMagic, 8);
  put<uint32_t>(f, kFpmapVersion);
  write_plan_binary(plan_, f);
  write(f);
  f.flush();
  if (!f) fail(path + ": write error");
}

Annf Annf::load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
  read_fpmap_header(f, path);
  FloorPlan plan = read_plan_binary(f, path);
  plan.source = path;
  Annf a = read(f, std::move(plan), path);
  f.peek();
  if (!f.eof()) fail(path + ": trailing data after the map (corrupt file)");
  return a;
}

}  // namespace fploc::annf