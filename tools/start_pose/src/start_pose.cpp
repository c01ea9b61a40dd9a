#include "fploc/tools/start_pose.h"

#include <google/protobuf/descriptor.h>

#include <filesystem>
#include <sstream>

#include "fploc/floorplan/building.h"

namespace fploc::tools {

std::vector<StartPlan> start_plans(const rt::LoadedGraph& g, const std::function<bool(const fploc::Node&)>& keep) {
  using google::protobuf::FieldDescriptor;
  std::vector<StartPlan> out;
  for (const auto& n : g.graph.node()) {
    if (n.disabled() || (keep && !keep(n))) continue;
    const auto opts = rt::node_options(n);
    if (!opts) continue;
    const auto* d = opts->GetDescriptor();
    const auto* r = opts->GetReflection();
    const auto* pf = d->FindFieldByName("plan");
    const auto* ipf = d->FindFieldByName("initial_pose");
    if (!pf || !ipf || pf->is_repeated() || pf->type() != FieldDescriptor::TYPE_MESSAGE ||
        ipf->type() != FieldDescriptor::TYPE_MESSAGE || ipf->is_repeated())
      continue;
    const auto& plan = r->GetMessage(*opts, pf);
    const auto* pd = plan.GetDescriptor();
    const auto* pr = plan.GetReflection();
    const auto* ff = pd->FindFieldByName("file");
    if (!ff || ff->type() != FieldDescriptor::TYPE_STRING) continue;
    StartPlan s;
    s.node = n.name();
    const std::string file = pr->GetString(plan, ff);
    if (file.empty()) continue;
    s.path = std::filesystem::path(file).is_absolute() || g.dir.empty()
                 ? file
                 : (std::filesystem::path(g.dir) / file).lexically_normal().string();
    if (const auto* lf = pd->FindFieldByName("layers"))
      for (int k = 0; k < pr->FieldSize(plan, lf); ++k) s.load.layer_globs.push_back(pr->GetRepeatedString(plan, lf, k));
    if (const auto* uf = pd->FindFieldByName("units")) s.load.units_override = pr->GetString(plan, uf);
    if (const auto* fl = pd->FindFieldByName("floor")) s.load.floor = pr->GetString(plan, fl);
    s.load.quiet = true;
    const auto set_flag = [&](const char* name) {
      const auto* f = d->FindFieldByName(name);
      return f && f->type() == FieldDescriptor::TYPE_BOOL && !f->is_repeated() && r->GetBool(*opts, f);
    };
    s.ignores_initial_pose = set_flag("wait_for_initial_pose") || set_flag("global_localization");
    if (r->HasField(*opts, ipf)) {
      const auto& ip = r->GetMessage(*opts, ipf);
      const auto* fx = ip.GetDescriptor()->FindFieldByName("x");
      const auto* fy = ip.GetDescriptor()->FindFieldByName("y");
      if (fx && fy && fx->type() == FieldDescriptor::TYPE_DOUBLE && fy->type() == FieldDescriptor::TYPE_DOUBLE) {
        s.has_initial_pose = true;
        s.x = ip.GetReflection()->GetDouble(ip, fx);
        s.y = ip.GetReflection()->GetDouble(ip, fy);
      }
    }
    out.push_back(std::move(s));
  }
  return out;
}

StartPoseCheck check_start_pose(const StartPlan& plan, double x, double y) {
  StartPoseCheck c;
  std::string where = plan.path;  // the plan (and floor) checked
  if (is_building_file(plan.path)) {
    BuildingLoadOptions bo;
    bo.quiet = true;
    const Building b = load_building(plan.path, bo);
    c.floor = b.floor(plan.load.floor).name;  // throws naming the floors
    c.where = locate_in_plan(load_floor_plan(b, c.floor, plan.load), {x, y});
    for (const auto& f : b.floors) {
      if (f.name == c.floor) continue;
      // Another floor holds the pose inside its drawn walls; one the node's layers/units cannot load is no answer
      // (and no reason to skip the check of its own floor).
      try {
        const PlanPosition o = locate_in_plan(load_floor_plan(b, f.name, plan.load), {x, y});
        if (o.inside_extent() && o.enclosed()) c.other_floors.push_back(f.name);
      } catch (const std::exception&) {
      }
    }
    where = "floor '" + c.floor + "' of " + plan.path;
  } else {
    c.where = locate_in_plan(load_floor_plan(plan.path, plan.load), {x, y});
  }
  const Box2& b = c.where.extent;
  std::ostringstream s;
  s << "(" << x << ", " << y << ")";
  if (!c.where.inside_extent()) {
    c.kind = c.where.outside_m > kFarOutsideM ? StartPoseKind::kFarOutside : StartPoseKind::kNearOutside;
    s << " lies outside its plan's extent (x " << b.min.x() << " .. " << b.max.x() << ", y " << b.min.y() << " .. "
      << b.max.y() << " m, " << where << ")";
  } else if (!c.where.enclosed()) {
    c.kind = StartPoseKind::kNotEnclosed;
    s << " lies within its plan's extent but not inside its drawn walls (plan elements in " << c.where.hits << " of "
      << c.where.directions << " directions, " << where << ")";
  } else {
    return c;
  }
  if (c.other_floors.size() == 1) {
    s << "; it lies inside floor '" << c.other_floors[0] << "' (--set " << plan.node << ".plan.floor=" << c.other_floors[0]
      << " to start there)";
  } else if (!c.other_floors.empty()) {
    s << "; it lies inside floors";
    for (size_t k = 0; k < c.other_floors.size(); ++k) s << (k ? ", '" : " '") << c.other_floors[k] << "'";
    s << " (--set " << plan.node << ".plan.floor=NAME to start on one)";
  }
  c.text = s.str();
  return c;
}

}  // namespace fploc::tools
