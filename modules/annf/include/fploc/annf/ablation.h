// Ablation-only settings of the ANNF (benchmarks, `fploc map validate|build --rule/--candidates`,
// tests): the readings of the paper's stopping rules and of its candidate choice that
// docs/notes/annf.md compares. The localizer and the nodes never include this header; they use the
// defaults of AnnfOptions (kChildLeafOrdered, kPassingElseAll).
#pragma once
#include <cstdint>
#include <string>

#include "fploc/annf/annf.h"

namespace fploc::annf {

// Readings of the paper's stopping rules ("If a child subfield shares the same two nearest elements
// with its parent field, it will not be further divided and set as a leaf field. If all four
// subfields ... have the same two nearest neighbours as their parent's, the division operation will
// be withdrawn").
enum class PaperRule : uint8_t {
  kChildLeaf = 0,      // A child equal to its parent becomes a leaf; all four equal -> undo split.
  kUndoOnly = 1,       // Only "all four equal -> undo"; children equal to the parent still divide.
  kChildLeafOrdered = 2,  // As kChildLeaf, "same" compares the ordered pair (1st, 2nd).
  kFull = 3,           // No stopping rule: every field divides to max_depth (upper bound on accuracy).
  // Bottom-up readings: every field is divided to max_depth first; a division is then withdrawn
  // (recursively, from the deepest level up) when all four children are leaves that share the
  // parent's nearest element (kCollapseFirst: what the authors' public demo does, reverse-engineered
  // from its leaf table, docs/notes/annf.md) or its ordered pair (kCollapsePair).
  kCollapseFirst = 4,
  kCollapsePair = 5,
};

// "We iterate over every element, check which fields they are passing through, ..." (paper mode):
// where a field's two elements are chosen from (AnnfOptions::paper_candidates).
enum class AnnfOptions::Candidates : uint8_t { kAll = 0, kPassingElseAll = 1, kPassingInherit = 2 };

static_assert(PaperRule{2} == PaperRule::kChildLeafOrdered && AnnfOptions::Candidates{1} == AnnfOptions::Candidates::kPassingElseAll,
              "the defaults written as numbers in annf.h");

const char* to_string(PaperRule r);
PaperRule parse_paper_rule(const std::string& s);  // "child-leaf" | "undo-only" | "child-leaf-ordered" | "full" |
                                                   // "collapse-first" | "collapse-pair"

}  // namespace fploc::annf