// make_lift_log: one LCM log of a lift ride between two floors, from two simulated runs (fploc-sim):
// run A on the lower floor's plan ends at rest; the robot then rides the lift up (IMU: the specific
// force grows and shrinks along gravity: 1 s at rest, `accel` m/s^2 for 2 s, cruise, -accel for 2 s; the
// LiDAR keeps seeing the last scan of A, the closed cab); at arrival run B (the upper floor, starting at
// rest) follows. Both floors share the building's x/y frame: B's plan is moved rigidly so that B starts
// where A ended (written to --b-plan-out), and B's ground truth with it.
//
//   make_lift_log --a A.lcm --a-gt A.tum --b B.lcm --b-gt B.tum --b-plan corridor.json --height 3.3
//                 --b-plan-out first.json --out lift.lcm --gt gt.tum --floors floors.txt
// floors.txt: "utime floor" per ground-truth pose (floor "ground" up to the lift's arrival, then "first"),
// and a line "# arrival UTIME" / "# ride_start UTIME" / "# lift X Y" for the test.
#include <fploc/ground_truth_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/scan_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fploc/floorplan/io.h"

namespace {

struct Event {
  int64_t utime;
  std::string channel;
  std::vector<uint8_t> data;
};

struct TumPose {
  double t, x, y, z, qx, qy, qz, qw;
};

std::vector<Event> read_log(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot open");
  std::vector<Event> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    const auto* d = static_cast<const uint8_t*>(e->data);
    out.push_back({e->timestamp, e->channel, std::vector<uint8_t>(d, d + e->datalen)});
  }
  return out;
}

std::vector<TumPose> read_tum(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::vector<TumPose> out;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    TumPose p;
    if (s >> p.t >> p.x >> p.y >> p.z >> p.qx >> p.qy >> p.qz >> p.qw) out.push_back(p);
  }
  if (out.empty()) throw std::runtime_error(path + ": no poses");
  return out;
}

double yaw_of(const TumPose& p) { return std::atan2(2 * (p.qw * p.qz + p.qx * p.qy), 1 - 2 * (p.qy * p.qy + p.qz * p.qz)); }

template <class M>
M decode(const Event& e) {
  M m;
  if (m.decode(e.data.data(), 0, int(e.data.size())) < 0) throw std::runtime_error("cannot decode " + e.channel);
  return m;
}

template <class M>
Event encode(int64_t utime, const std::string& ch, const M& m) {
  Event e{utime, ch, std::vector<uint8_t>(size_t(m.getEncodedSize()))};
  m.encode(e.data.data(), 0, int(e.data.size()));
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  std::map<std::string, std::string> a;
  for (int i = 1; i + 1 < argc; i += 2) a[argv[i]] = argv[i + 1];
  for (const char* k : {"--a", "--a-gt", "--b", "--b-gt", "--b-plan", "--b-plan-out", "--out", "--gt", "--floors"})
    if (!a.count(k)) {
      std::cerr << "make_lift_log: " << k << " is required\n";
      return 2;
    }
  const double height = a.count("--height") ? std::stod(a["--height"]) : 3.3;
  const double accel = a.count("--accel") ? std::stod(a["--accel"]) : 0.5;
  const std::string lower = a.count("--lower") ? a["--lower"] : "ground", upper = a.count("--upper") ? a["--upper"] : "first";
  try {
    const auto ea = read_log(a["--a"]), eb = read_log(a["--b"]);
    const auto ga = read_tum(a["--a-gt"]), gb = read_tum(a["--b-gt"]);
    // The last scan and the IMU at rest at the end of A.
    const Event* last_scan = nullptr;
    Eigen::Vector3d f_rest = Eigen::Vector3d::Zero(), w_rest = Eigen::Vector3d::Zero();
    int n_rest = 0;
    int64_t a_end = 0;
    for (const auto& e : ea) {
      if (e.channel == "OS1_SCAN") last_scan = &e;
      a_end = std::max(a_end, e.utime);
    }
    if (!last_scan) throw std::runtime_error(a["--a"] + ": no OS1_SCAN");
    for (auto it = ea.rbegin(); it != ea.rend() && n_rest < 50; ++it)
      if (it->channel == "OS1_IMU") {
        const auto m = decode<fploc::imu_t>(*it);
        f_rest += Eigen::Vector3d(m.accel[0], m.accel[1], m.accel[2]);
        w_rest += Eigen::Vector3d(m.gyro[0], m.gyro[1], m.gyro[2]);
        ++n_rest;
      }
    if (n_rest == 0) throw std::runtime_error(a["--a"] + ": no OS1_IMU");
    f_rest /= n_rest;
    w_rest /= n_rest;
    const fploc::scan_t scan_a = decode<fploc::scan_t>(*last_scan);

    // The ride: 1 s rest, accelerate 2 s, cruise, brake 2 s; arrival at its end.
    const double ta = 2.0, v = accel * ta, tc = std::max(0.0, (height - accel * ta * ta) / v);
    const int64_t ride_start = a_end + 1'000'000, arrival = ride_start + int64_t((2 * ta + tc) * 1e6);
    auto a_up = [&](double s) { return s < 0 ? 0.0 : s < ta ? accel : s < ta + tc ? 0.0 : s < 2 * ta + tc ? -accel : 0.0; };
    auto h_at = [&](double s) {  // height gained s seconds after the ride's start
      if (s <= 0) return 0.0;
      if (s < ta) return 0.5 * accel * s * s;
      if (s < ta + tc) return 0.5 * accel * ta * ta + v * (s - ta);
      const double u = std::min(s - ta - tc, ta);
      return 0.5 * accel * ta * ta + v * tc + v * u - 0.5 * accel * u * u;
    };
    std::vector<Event> out;
    for (const auto& e : ea) out.push_back(e);
    const TumPose pa = ga.back();
    std::vector<TumPose> gt = ga;
    std::vector<std::string> gt_floor(ga.size(), lower);
    // IMU at 100 Hz and the last scan every 0.1 s from A's end to the arrival.
    // Sequence numbers continue A's (the pipeline drops a scan whose seq is not after the previous one).
    int64_t imu_seq = 0, scan_seq = 0;
    for (const auto& e : ea) {
      if (e.channel == "OS1_SCAN") scan_seq = std::max(scan_seq, decode<fploc::scan_t>(e).seq + 1);
      if (e.channel == "OS1_IMU") imu_seq = std::max(imu_seq, decode<fploc::imu_t>(e).seq + 1);
    }
    const double g = f_rest.norm();
    for (int64_t u = a_end + 10'000; u < arrival; u += 10'000) {
      fploc::imu_t m{};
      m.utime = m.accel_utime = m.gyro_utime = u;
      m.seq = imu_seq++;
      const Eigen::Vector3d f = f_rest * ((g + a_up((u - ride_start) * 1e-6)) / g);
      for (int i = 0; i < 3; ++i) m.accel[i] = f[i], m.gyro[i] = w_rest[i];
      m.source = "sim";
      out.push_back(encode(u, "OS1_IMU", m));
    }
    for (int64_t u = last_scan->utime + 100'000; u < arrival; u += 100'000) {
      fploc::scan_t s = scan_a;
      const int64_t d = u - scan_a.utime;
      s.utime = u;
      s.seq = scan_seq++;
      for (auto& c : s.column_utime) c += d;
      out.push_back(encode(u, "OS1_SCAN", s));
      TumPose p = pa;
      p.t = u * 1e-6;
      p.z = pa.z + h_at((u - ride_start) * 1e-6);  // absolute (the lower floor is at 0)
      gt.push_back(p);
      fploc::ground_truth_t gm{};
      gm.utime = u;
      gm.seq = scan_seq;
      gm.position[0] = p.x, gm.position[1] = p.y, gm.position[2] = p.z;
      gm.orientation[0] = p.qx, gm.orientation[1] = p.qy, gm.orientation[2] = p.qz, gm.orientation[3] = p.qw;
      gm.scenario = "lift";
      out.push_back(encode(u, "FPLOC_GROUND_TRUTH", gm));
      gt_floor.push_back(lower);
    }
    // B, moved so that it starts where A ended, its first scan at the arrival.
    int64_t b0 = INT64_MAX;
    for (const auto& e : eb)
      if (e.channel == "OS1_SCAN") b0 = std::min(b0, decode<fploc::scan_t>(e).utime);
    const int64_t shift = arrival - b0;
    const int64_t scan_seq0 = scan_seq, imu_seq0 = imu_seq;
    const TumPose pb = gb.front();
    const double dyaw = yaw_of(pa) - yaw_of(pb);
    const Eigen::Rotation2Dd R(dyaw);
    const Eigen::Vector2d tr = Eigen::Vector2d(pa.x, pa.y) - R * Eigen::Vector2d(pb.x, pb.y);
    for (const auto& e : eb) {
      if (e.channel == "OS1_SCAN") {
        auto s = decode<fploc::scan_t>(e);
        s.utime += shift;
        s.seq += scan_seq0;
        for (auto& c : s.column_utime) c += shift;
        out.push_back(encode(e.utime + shift, e.channel, s));
      } else if (e.channel == "OS1_IMU") {
        auto m = decode<fploc::imu_t>(e);
        m.utime += shift, m.accel_utime += shift, m.gyro_utime += shift;
        m.seq += imu_seq0;
        out.push_back(encode(e.utime + shift, e.channel, m));
      } else if (e.channel == "FPLOC_GROUND_TRUTH") {
        auto m = decode<fploc::ground_truth_t>(e);
        m.utime += shift;
        m.seq += scan_seq0;
        const Eigen::Vector2d xy = R * Eigen::Vector2d(m.position[0], m.position[1]) + tr;
        m.position[0] = xy.x(), m.position[1] = xy.y();
        m.position[2] += height;  // absolute z (pose_t convention): the upper floor's elevation + the height above it
        const Eigen::Quaterniond o = Eigen::Quaterniond(Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ())) *
                                     Eigen::Quaterniond(m.orientation[3], m.orientation[0], m.orientation[1], m.orientation[2]);
        m.orientation[0] = o.x(), m.orientation[1] = o.y(), m.orientation[2] = o.z(), m.orientation[3] = o.w();
        const Eigen::Vector2d v = R * Eigen::Vector2d(m.linear_velocity[0], m.linear_velocity[1]);
        m.linear_velocity[0] = v.x(), m.linear_velocity[1] = v.y();
        out.push_back(encode(e.utime + shift, e.channel, m));
      }
    }
    const Eigen::Quaterniond qr(Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()));
    for (const auto& p : gb) {
      TumPose q = p;
      q.t = p.t + shift * 1e-6;
      const Eigen::Vector2d xy = R * Eigen::Vector2d(p.x, p.y) + tr;
      q.x = xy.x(), q.y = xy.y();
      q.z = p.z + height;  // absolute
      const Eigen::Quaterniond o = qr * Eigen::Quaterniond(p.qw, p.qx, p.qy, p.qz);
      q.qx = o.x(), q.qy = o.y(), q.qz = o.z(), q.qw = o.w();
      gt.push_back(q);
      gt_floor.push_back(upper);
    }
    std::stable_sort(out.begin(), out.end(), [](const Event& x, const Event& y) { return x.utime < y.utime; });
    {
      lcm::LogFile log(a["--out"], "w");
      if (!log.good()) throw std::runtime_error(a["--out"] + ": cannot open for writing");
      for (const auto& e : out) {
        lcm::LogEvent le;
        le.eventnum = 0;
        le.timestamp = e.utime;
        le.channel = e.channel;
        le.datalen = int32_t(e.data.size());
        le.data = const_cast<uint8_t*>(e.data.data());
        if (log.writeEvent(&le) != 0) throw std::runtime_error(a["--out"] + ": write failed");
      }
    }
    std::ofstream gf(a["--gt"]), ff(a["--floors"]);
    gf << std::fixed << std::setprecision(6);
    ff << "# ride_start " << ride_start << "\n# arrival " << arrival << "\n# lift " << pa.x << " " << pa.y << "\n";
    for (size_t i = 0; i < gt.size(); ++i) {
      const auto& p = gt[i];
      gf << p.t << " " << p.x << " " << p.y << " " << p.z << " " << p.qx << " " << p.qy << " " << p.qz << " " << p.qw << "\n";
      ff << std::llround(p.t * 1e6) << " " << gt_floor[i] << "\n";
    }
    // B's plan in the building frame.
    fploc::FloorPlan plan = fploc::load_floor_plan(a["--b-plan"]);
    const Eigen::Vector2d c = tr;
    for (auto& el : plan.elements) {
      el.a = R * el.a + c;
      el.b = R * el.b + c;
      el.c = R * el.c + c;
      el.a0 += dyaw;
      el.a1 += dyaw;
    }
    fploc::save_floor_plan(plan, a["--b-plan-out"]);
    std::cerr << "make_lift_log: A ends at (" << pa.x << ", " << pa.y << "), ride " << height << " m from "
              << ride_start << " to " << arrival << " us, B shifted by " << shift << " us, " << out.size() << " events\n";
  } catch (const std::exception& e) {
    std::cerr << "make_lift_log: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
