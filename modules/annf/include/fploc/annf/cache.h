// A cache of built ANNFs on disk, so the nodes of a graph (matcher, optimizer, relocalizer, amcl)
// and later runs build each floor's field once.
//
//   std::string note;
//   std::shared_ptr<const Annf> a = fploc::annf::cached_annf(plan, options, &note);
//
// Key: a hash of the plan's content as loaded (every element's kind, coordinates and layer name,
// i.e. what the file says after units and layer selection) and of the options saved with the field
// (mode, rule, readings, root length, depth, candidates, refinement, margin), plus the .fpmap
// version. Any change of the plan file that changes an element, or of an option, is a new key; the
// old file is simply not used again. A hit is verified (the stored plan and options must equal the
// requested ones exactly), so a hash collision or a damaged file means a rebuild, never a wrong field.
//
// Folder: `dir` when given, else $FPLOC_ANNF_CACHE ("off" disables the cache), else
// $XDG_CACHE_HOME/fploc/annf, else $HOME/.cache/fploc/annf. Files: <key>.fpmap (the usual map
// format, `fploc map render --map` reads them).
//
// Concurrency: builders of the same key take an exclusive lock (flock on <key>.lock); the first
// builds and writes <key>.fpmap through a temporary file + rename (readers never see a partial
// file), the others wait and then load it. Unwritable folder or any cache error: the field is
// built in memory and the note says why (the cache never makes a start fail).
#pragma once
#include <memory>
#include <string>

#include "fploc/annf/annf.h"

namespace fploc::annf {

std::string default_annf_cache_dir();  // "" when the cache is off
std::string annf_cache_key(const FloorPlan& plan, const AnnfOptions& options);  // 16 hex digits

// `note` (optional) gets what happened (also printed as one line on stderr, "fploc annf: ..."): "ANNF cache hit DIR/KEY.fpmap (12 ms)", "built ANNF (...)
// in 17 s, cached as ...", or "built ANNF (...), not cached: why".
std::shared_ptr<const Annf> cached_annf(const FloorPlan& plan, const AnnfOptions& options, std::string* note = nullptr,
                                        const std::string& dir = "");

}  // namespace fploc::annf