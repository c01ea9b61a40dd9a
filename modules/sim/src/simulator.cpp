#include "fploc/sim/simulator.h"

#include "fploc/sim/beam_patterns.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "fploc/core/rng.h"

namespace fploc::sim {
namespace {

double dist_to_path(const std::vector<Eigen::Vector2d>& path, const Eigen::Vector2d& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& q : path) d = std::min(d, (q - p).squaredNorm());
  return std::sqrt(d);
}

}  // namespace

Simulator::Simulator(FloorPlan plan, SimulatorOptions opt) : opt_(std::move(opt)) {
  std::string err;
  if (!scenario_spec(opt_.scenario, spec_, &err)) throw std::runtime_error(err);
  if (spec_.plan_kind == "building")
    throw std::runtime_error("scenario " + spec_.name +
                             " is a journey through the demo building: give the building (--plan data/buildings/demo-building.pbtxt)");
  init(std::move(plan));
}

Simulator::Simulator(const Building& building, const std::string& floor, SimulatorOptions opt,
                     const PlanLoadOptions& plan_options)
    : opt_(std::move(opt)) {
  std::string err;
  if (!scenario_spec(opt_.scenario, spec_, &err)) throw std::runtime_error(err);
  building_ = std::make_shared<Building>(building);
  floor_ = floor.empty() ? 0 : building_->floor_index(floor);
  if (floor_ < 0) (void)building_->floor(floor);  // throws naming the floors
  init_building(plan_options);
}

void Simulator::init_building(const PlanLoadOptions& plan_options) {
  const Building& b = *building_;
  if (!opt_.world_file.empty() || opt_.perturb.any())
    throw std::runtime_error("world perturbations (--perturb, --world) are not supported on a building (" + b.source +
                             "); give one floor's plan file instead");
  const bool journey = spec_.plan_kind == "building";
  const size_t n = b.floors.size();
  std::vector<FloorPlan> plans(n);
  floor_worlds_.resize(n);
  grounds_.resize(n);
  lift_worlds_.resize(b.connections.size());
  FloorWorldOptions fo;
  fo.thresholds = opt_.thresholds;
  fo.seed = opt_.seed;
  for (size_t i = 0; i < n; ++i) {
    grounds_[i].elevation = b.floors[i].elevation;
    if (!journey && int(i) != floor_) continue;
    plans[i] = load_floor_plan(b, b.floors[i].name, plan_options);
    std::string note;
    floor_worlds_[i] = make_floor_world(b, int(i), plans[i], fo, &grounds_[i], &note);
    info_ += note + "\n";
  }
  if (journey) {
    auto j = std::make_unique<Journey>(b, spec_.legs, spec_.speed, opt_.seed, grounds_);
    // The journeys are drawn for the demo building: refuse a building they would drive through.
    for (size_t i = 0; i < n; ++i) {
      const auto pts = j->sample_path_on_floor(int(i), 0.05);
      if (pts.empty()) continue;
      const double clr = min_clearance(plans[i], pts);
      if (clr < 0.3)
        throw std::runtime_error("scenario " + spec_.name + " is drawn for the demo building (data/buildings/demo-building.pbtxt); "
                                 "its path comes within " + std::to_string(clr) + " m of an element of floor '" +
                                 b.floors[i].name + "' of " + b.source);
    }
    for (size_t c = 0; c < b.connections.size(); ++c)
      if (b.connections[c].kind == ConnectionKind::kLift) lift_worlds_[c] = make_lift_car_world(b.connections[c]);
    floor_ = j->start_floor();
    journey_ = j.get();
    motion_ = std::move(j);
    for (const auto& c : journey_->floor_changes()) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "floor change at %.2f s: %s -> %s (%s)\n", c.t, b.floors[size_t(c.from)].name.c_str(),
                    b.floors[size_t(c.to)].name.c_str(), c.how.c_str());
      info_ += buf;
    }
  } else {
    const FloorPlan& plan = plans[size_t(floor_)];
    if (spec_.plan_kind == "any") {
      // auto-loop keeps to the floor: stairs, ramps and lifts are walls for the planner.
      FloorPlan planning = plan;
      for (const auto& e : connection_outlines(b, floor_, false)) planning.elements.push_back(e);
      const AutoLoopResult r = plan_auto_loop(planning);
      spec_.control = r.control;
      spec_.closed = true;
      spec_.length = 0;
      info_ += r.info + "\n";
    } else {
      const Motion probe(spec_.control, spec_.closed, spec_.speed, spec_.length, 0);
      const double clr = min_clearance(plan, probe.sample_path(0.05));
      if (clr < 0.4)
        throw std::runtime_error("scenario " + spec_.name + " is drawn for the demo " + spec_.plan_kind +
                                 " plan; its path comes within " + std::to_string(clr) + " m of an element of floor '" +
                                 b.floors[size_t(floor_)].name + "' of " + b.source + " (use auto-loop-" + spec_.speed_name + ")");
    }
    MotionConfig mc;
    const FloorGround* g = &grounds_[size_t(floor_)];
    mc.ground = [g](double, const Eigen::Vector2d& p) { return g->elevation + g->wheel_at(p); };
    motion_ = std::make_unique<Motion>(spec_.control, spec_.closed, spec_.speed, spec_.length, opt_.seed, mc);
  }
  world_ = floor_worlds_[size_t(floor_)].get();
  if (opt_.clutter) {
    int boxes = 0, people = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!floor_worlds_[i]) continue;
      const auto path = journey_ ? journey_->sample_path_on_floor(int(i), 0.1) : motion_->sample_path(0.1);
      add_clutter(*floor_worlds_[i], path, 0.1 * double(path.size()), mix_seed(0xC1u, i), &boxes, &people);
    }
    info_ += "clutter: " + std::to_string(boxes) + " furniture boxes, " + std::to_string(people) + " people\n";
  }
  if (opt_.wall_clutter > 0) add_wall_clutter();
  if (!spec_.ceilings.empty()) {
    ceiling_map_ = make_ceiling_map(spec_.ceilings, world_->bounds(), world_->config().ceiling_height_m, opt_.seed);
    apply_ceiling_map(ceiling_map_, *world_);
    info_ += "ceilings: " + spec_.ceilings + ", " + std::to_string(ceiling_map_.areas.size()) + " areas, " +
             std::to_string(ceiling_map_.objects.size()) + " hanging objects\n";
  }
  finish();
}

World& Simulator::world_at(double t, double* z0) {
  if (journey_) {
    const double rel = t - opt_.t0_s;
    int lift = -1;
    double cz = 0;
    if (journey_->in_closed_lift(rel, &lift, &cz) && lift >= 0 && lift_worlds_[size_t(lift)]) {
      *z0 = cz;
      return *lift_worlds_[size_t(lift)];
    }
    const int f = journey_->floor_at(rel);
    *z0 = grounds_[size_t(f)].elevation;
    return *floor_worlds_[size_t(f)];
  }
  *z0 = building_ ? grounds_[size_t(floor_)].elevation : 0.0;
  return *world_;
}

int Simulator::floor_at(double t) const { return journey_ ? journey_->floor_at(t - opt_.t0_s) : floor_; }

std::string Simulator::floor_name(int floor) const {
  if (!building_ || floor < 0 || floor >= int(building_->floors.size())) return "";
  return building_->floors[size_t(floor)].name;
}

std::string Simulator::state_at(double t) const {
  if (journey_) return journey_->state_at(t - opt_.t0_s);
  if (building_) {
    const Eigen::Vector3d p = motion_->pose(t - opt_.t0_s).translation();
    for (const auto& in : grounds_[size_t(floor_)].inclines)
      if (in.contains(p.head<2>())) return "ramp";
  }
  return "drive";
}

std::vector<FloorChange> Simulator::floor_changes() const {
  return journey_ ? journey_->floor_changes() : std::vector<FloorChange>{};
}

void Simulator::init(FloorPlan plan) {
  std::string err;
  const bool own_plan = !plan.elements.empty();
  if (plan.elements.empty()) {
    if (spec_.plan_kind == "room") plan = demo_room_plan();
    else if (spec_.plan_kind == "corridor") plan = demo_corridor_plan();
    else throw std::runtime_error("scenario " + spec_.name + " needs a floor plan (--plan FILE)");
  }
  if (spec_.plan_kind == "any") {
    const AutoLoopResult r = plan_auto_loop(plan);
    spec_.control = r.control;
    spec_.closed = true;
    spec_.length = 0;
    info_ += r.info + "\n";
  }
  if (own_plan && spec_.plan_kind != "any") {
    // The paper scenarios are drawn for the demo plans: refuse a plan they would drive through.
    const Motion probe(spec_.control, spec_.closed, spec_.speed, spec_.length, 0);
    const double clr = min_clearance(plan, probe.sample_path(0.05));
    if (clr < 0.4)
      throw std::runtime_error("scenario " + spec_.name + " is drawn for the demo " + spec_.plan_kind +
                               " plan; its path comes within " + std::to_string(clr) + " m of an element of " +
                               plan.source + " (use auto-loop-" + spec_.speed_name + " for other plans)");
  }
  WorldConfig wc;
  wc.ceiling_height_m = opt_.ceiling_height_m > 0 ? opt_.ceiling_height_m : spec_.ceiling_m;
  motion_ = std::make_unique<Motion>(spec_.control, spec_.closed, spec_.speed, spec_.length, opt_.seed);
  if (!opt_.world_file.empty() || opt_.perturb.any()) {
    edit_ = std::make_unique<WorldEdit>(
        !opt_.world_file.empty() ? load_world_file(opt_.world_file, plan, opt_.world_layers, opt_.world_units)
                                 : perturb_world(plan, motion_->sample_path(0.1), opt_.perturb, opt_.seed));
    own_world_ = std::make_unique<World>(edit_->world, wc);
    world_ = own_world_.get();
    for (const auto& f : edit_->furniture) world_->add_furniture(f);
    for (const auto& p : edit_->people) world_->add_person(p);
    opt_.wall_clutter = std::max(opt_.wall_clutter, edit_->wall_clutter);
    info_ += "world: " + edit_->source + " (" + std::to_string(edit_->world.elements.size()) + " walls/pillars, " +
             std::to_string(edit_->added.size()) + " added, " + std::to_string(edit_->people.size()) + " extra people)\n";
  } else {
    own_world_ = std::make_unique<World>(plan, wc);
    world_ = own_world_.get();
  }
  if (!spec_.ceilings.empty()) {
    ceiling_map_ = make_ceiling_map(spec_.ceilings, world_->bounds(), wc.ceiling_height_m, opt_.seed);
  } else if (opt_.ceiling_patches && spec_.plan_kind != "corridor") {
    // A sloped patch in one corner of the building (rising 0.15 m per metre) and a missing patch (an
    // opening, 2.0 x 1.5 m) at the centre of the plan.
    const Box2 b = world_->bounds();
    CeilingPatch slope;
    slope.box.min = b.min + 0.75 * b.size();
    slope.box.max = b.max;
    slope.h0 = wc.ceiling_height_m;
    slope.slope = Eigen::Vector2d(0.15, 0.0);
    world_->add_ceiling_patch(slope);
    CeilingPatch open;
    const Eigen::Vector2d c = 0.5 * (b.min + b.max);
    open.box.min = c - Eigen::Vector2d(1.0, 0.75);
    open.box.max = c + Eigen::Vector2d(1.0, 0.75);
    open.open = true;
    world_->add_ceiling_patch(open);
  }
  if (opt_.clutter) add_clutter();
  if (opt_.wall_clutter > 0) add_wall_clutter();
  if (!spec_.ceilings.empty()) {  // after the clutter: hanging objects do not block furniture placement
    apply_ceiling_map(ceiling_map_, *world_);
    info_ += "ceilings: " + spec_.ceilings + ", " + std::to_string(ceiling_map_.areas.size()) + " areas, " +
             std::to_string(ceiling_map_.objects.size()) + " hanging objects\n";
  }
  finish();
}

void Simulator::finish() {
  std::string err;
  SensorConfig sc;
  if (!opt_.metadata.empty()) {
    if (!load_beam_intrinsics_json(opt_.metadata, sc.beams, &err)) throw std::runtime_error(err);
    beam_source_ = opt_.metadata;
  } else {
    sc.beams = beam_pattern(opt_.beams, opt_.shared_dir, &beam_source_);
  }
  sc.width = opt_.width;
  sc.rate_hz = opt_.rate_hz;
  sc.range_noise_m = opt_.range_noise_m;
  sc.dropout = opt_.dropout;
  lidar_ = std::make_unique<LidarSim>(sc);
  ImuConfig ic;
  ic.rate_hz = opt_.imu_rate_hz;
  imu_ = simulate_imu(*motion_, ic, opt_.seed);
  num_frames_ = int(std::floor(motion_->duration() * opt_.rate_hz));
}

// Tall cabinets (2 m, 0.4 m deep) against the walls: every wall segment of at least 0.8 m is cut into
// pieces of about 1 m on the side(s) of the wall inside the building; pieces in random order get a
// cabinet (unless it would stand on the path or against another cabinet) until wall_clutter of the
// wall length is covered.
void Simulator::add_wall_clutter() {
  Rng rng(mix_seed(opt_.seed, 0xCAB1u));
  const auto path = motion_->sample_path(0.1);
  const double depth = 0.4, gap = 0.03;
  struct Piece {
    Furniture f;
    double len;
  };
  std::vector<Piece> pieces;
  double wall_len = 0, covered = 0;
  const FloorPlan plan = world_->plan();
  for (const auto& e : plan.elements) {
    if (e.kind != ElementKind::kSegment) continue;
    const Eigen::Vector2d d = e.b - e.a;
    const double len = d.norm();
    if (len < 0.8) continue;
    const Eigen::Vector2d u = d / len, n(-u.y(), u.x());
    const int np = std::max(1, int(std::lround(len)));
    const double pl = len / np;
    for (int i = 0; i < np; ++i) {
      const Eigen::Vector2d mid = e.a + u * (pl * (i + 0.5));
      for (double side : {1.0, -1.0}) {
        const Eigen::Vector2d c = mid + side * n * (gap + depth / 2);
        // Outside the building, or inside a wall's thickness (another element closer than the box's depth).
        if (std::isnan(world_->ceiling_at(c.x(), c.y())) || world_->static_clearance(c) < depth / 2 + gap - 1e-3) continue;
        wall_len += pl;
        Piece p;
        p.f.center = c;
        p.f.yaw = std::atan2(u.y(), u.x());
        p.f.half = Eigen::Vector2d(pl / 2 - 0.01, depth / 2);
        p.f.z0 = 0;
        p.f.z1 = 2.0;
        p.f.reflectivity = 35;
        p.len = pl;
        pieces.push_back(p);
      }
    }
  }
  for (size_t i = pieces.size(); i > 1; --i) std::swap(pieces[i - 1], pieces[size_t(rng.uniform() * double(i)) % i]);
  for (const auto& p : pieces) {
    if (covered >= opt_.wall_clutter * wall_len) break;
    if (dist_to_path(path, p.f.center) < p.f.half.y() + 0.35) continue;  // the dolly's path stays free
    if (world_->static_clearance(p.f.center) < depth / 2 + gap - 1e-3) continue;  // another cabinet there
    world_->add_furniture(p.f);
    covered += p.len;
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, "wall clutter: %.1f m of %.1f m of walls behind 2 m cabinets (%.0f %%)\n", covered,
                wall_len, wall_len > 0 ? 100 * covered / wall_len : 0.0);
  info_ += buf;
}

void Simulator::add_clutter() {
  int boxes = 0, people = 0;
  add_clutter(*world_, motion_->sample_path(0.1), motion_->length(), 0xC1u, &boxes, &people);
  info_ += "clutter: " + std::to_string(boxes) + " furniture boxes, " + std::to_string(people) + " people\n";
}

void Simulator::add_clutter(World& w, const std::vector<Eigen::Vector2d>& path, double len, uint64_t salt, int* n_boxes,
                            int* n_people) {
  if (path.empty()) return;
  Rng rng(mix_seed(opt_.seed, salt));
  // Not on ramps or stairs, nor in a lift (buildings).
  auto off_limits = [&](const Eigen::Vector2d& p) {
    if (w.ground_at(p.x(), p.y()) != 0) return true;
    if (building_)
      for (const auto& c : building_->connections)
        if (c.contains(p)) return true;
    return false;
  };
  struct Kind {
    double hx, hy, h;
    uint8_t refl;
  };
  const Kind kinds[] = {{0.8, 0.4, 0.75, 30}, {0.5, 0.25, 1.9, 50}, {0.25, 0.25, 0.9, 20}, {0.6, 0.3, 1.1, 40}};
  const int want_boxes = std::clamp(int(len / 6.0), 4, 12);
  int boxes = 0;
  for (int attempt = 0; attempt < 400 && boxes < want_boxes; ++attempt) {
    const auto& base = path[size_t(rng.uniform() * path.size()) % path.size()];
    const double a = rng.uniform(0, 2 * M_PI), r = rng.uniform(1.0, 4.0);
    const Kind& k = kinds[size_t(rng.uniform() * 4) % 4];
    Furniture f;
    f.center = base + r * Eigen::Vector2d(std::cos(a), std::sin(a));
    f.yaw = rng.uniform(0, M_PI);
    f.half = Eigen::Vector2d(k.hx, k.hy);
    f.z0 = 0;
    f.z1 = k.h;
    f.reflectivity = k.refl;
    const double rad = f.half.norm();
    if (std::isnan(w.ceiling_at(f.center.x(), f.center.y()))) continue;
    if (w.static_clearance(f.center) < rad + 0.05) continue;
    if (dist_to_path(path, f.center) < rad + 0.6) continue;
    if (off_limits(f.center)) continue;
    w.add_furniture(f);
    ++boxes;
  }
  int people = 0;
  for (int attempt = 0; attempt < 400 && people < 2; ++attempt) {
    const auto& base = path[size_t(rng.uniform() * path.size()) % path.size()];
    const double a = rng.uniform(0, 2 * M_PI), r = rng.uniform(1.5, 4.0);
    const Eigen::Vector2d p0 = base + r * Eigen::Vector2d(std::cos(a), std::sin(a));
    const double b = rng.uniform(0, 2 * M_PI), plen = rng.uniform(3.0, 6.0);
    const Eigen::Vector2d p1 = p0 + plen * Eigen::Vector2d(std::cos(b), std::sin(b));
    bool ok = true;
    for (int i = 0; i <= 20 && ok; ++i) {
      const Eigen::Vector2d q = p0 + (p1 - p0) * (i / 20.0);
      if (std::isnan(w.ceiling_at(q.x(), q.y())) || w.static_clearance(q) < 0.45 || dist_to_path(path, q) < 1.0 ||
          off_limits(q))
        ok = false;
    }
    if (!ok) continue;
    Person p;
    p.path = {p0, p1};
    p.speed = rng.uniform(0.6, 1.3);
    p.phase_s = rng.uniform(0, 10);
    w.add_person(p);
    ++people;
  }
  *n_boxes += boxes;
  *n_people += people;
}

void Simulator::frame(int k, SimScan& out) {
  const double t0 = frame_time(k);
  const SensorTrajectory& m = *motion_;
  const double base = opt_.t0_s;
  // Buildings: the world of the floor (or closed lift car) the sensor is in, whose z = 0 is at z0.
  double z0 = 0;
  World& w = world_at(t0, &z0);
  if (z0 == 0) {
    lidar_->simulate(w, [&m, base](double t) { return m.pose(t - base); }, t0, k, opt_.seed, out);
  } else {
    lidar_->simulate(w, [&m, base, z0](double t) {
      Eigen::Isometry3d p = m.pose(t - base);
      p.translation().z() -= z0;
      return p;
    }, t0, k, opt_.seed, out);
    out.gt = StampedPose::from(out.gt.t, m.pose(out.gt.t - base));  // absolute
  }
}

StampedPose Simulator::ground_truth(double t) const { return StampedPose::from(t, motion_->pose(t - opt_.t0_s)); }

}  // namespace fploc::sim
