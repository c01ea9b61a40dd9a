// The option checks a node does at start, without starting it (`fploc launch --check` runs them too, so a
// value the node would refuse is not first found when the graph runs).
#pragma once
#include <google/protobuf/message.h>

#include <sstream>
#include <stdexcept>
#include <string>

#include <options/common.pb.h>

namespace fploc::config {

// An option value a node refuses (out of range, an unknown name): what() is "BLOCK.FIELD: why" (e.g.
// "matcher.loss: unknown loss 'x' (use ...)"); `field` is the option's path inside its block ("loss",
// "wheel.seed"), so a graph check can point at its line.
struct OptionError : std::runtime_error {
  OptionError(const std::string& block, std::string field_path, const std::string& why)
      : std::runtime_error(block + "." + field_path + ": " + why), field(std::move(field_path)) {}
  std::string field;
};

// An option where 0 means "the default" and only a value > 0 is meaningful: true when it is given (> 0),
// false for 0; a negative value is an OptionError ("must be > 0 (0 = the default), got -3"), not the
// default (it was taken as the default without a word). Options whose proto comment gives a negative value
// a meaning (max_points -1 = all, "negative = off") are not checked with it.
template <class T>
bool given(T value, const char* block, const char* field) {
  if (value < 0) {
    std::ostringstream v;
    v << value;
    throw OptionError(block, field, "must be > 0 (0 = the default), got " + v.str());
  }
  return value > 0;
}

// `lookup` of matcher/optimizer/relocalizer: "" (the default) or one of matcher::lookup_names() (the list
// the map builder itself checks against); else an OptionError naming the valid ones.
void check_lookup(const std::string& lookup, const char* block);
// A node that cannot run without a plan (matcher, optimizer, relocalizer, amcl, ndt, plan_diff, grid2d):
// an empty plan.file is an OptionError "BLOCK.plan.file: no floor plan given".
void check_plan_given(const PlanSource& plan, const char* block);

// Maps `options` (one of Node.options' messages) to every Config the node builds from it, i.e. runs the
// same checks (the config_of functions of this library). Throws OptionError (or std::runtime_error) as the
// node's setup would; options with no mapping here pass. Files are not read (launch's check_files does).
void check_options(const google::protobuf::Message& options);
// The options' plan, for the nodes that cannot run without one (check_plan_given): `fploc launch --check`
// runs it beside check_options (which also maps option blocks that are not complete graphs, e.g. in tests).
void check_plan_required(const google::protobuf::Message& options);

}  // namespace fploc::config
