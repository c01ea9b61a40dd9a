// fploc import RECORDING [--list] [--json] [--out LOG.lcm] [--topics T,...] [--start S] [--end S] ...
// ROS 1 bags (2.0; none/bz2/lz4 chunks), ROS 2 MCAP (none/zstd/lz4 chunks, CDR) and ROS 2 rosbag2 sqlite3 bags (.db3
// files or the bag folder, CDR) -> an LCM log that
// fploc replay and lcm-logplayer play:
//   ouster_ros/PacketMsg (+ the std_msgs/String metadata topic) -> the packets as they are: os1_packet_t on
//       OS1_LIDAR_PACKETS / OS1_IMU_PACKETS, os1_metadata_t on OS1_METADATA, decoded on replay by the OS-1
//       and IMU drivers (graphs/replay-packets.pbtxt) as the live sensor's packets; with --decode:
//       scan_t on OS1_SCAN, imu_t on OS1_IMU decoded here by the same OS-1 code (same scans)
//   sensor_msgs/PointCloud2 -> the clouds as they are: point_cloud2_t on POINT_CLOUD (bytes + field layout),
//       converted to scan_t on replay by the cloud-to-scan node (graphs/replay-clouds.pbtxt); with --decode:
//       scan_t on OS1_SCAN converted here by the same code (rings from the ring field or the elevations)
//   sensor_msgs/Imu -> imu_t on OS1_IMU;  sensor_msgs/LaserScan -> laser_scan_t on LASER_SCAN
//   nav_msgs/Odometry -> pose_t on WHEEL_ODOM (the odometry input of graphs/lidar2d.pbtxt's matcher, optimizer,
//       grid2d and AMCL; in its own odometry frame, floor_index -1)
//   nav_msgs/Odometry, tf2_msgs/TFMessage -> a TUM file (--tum-out, --tf-parent/--tf-child or --odom-topic)
// A second topic that would go to the same channel gets CHANNEL_<topic>; --channel TOPIC=CH overrides.
// Bad input: one error with the byte offset and record; the log holds everything read before it.
#include <fploc/imu_t.hpp>
#include <fploc/point_cloud2_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/scan_t.hpp>

#include <CLI/CLI.hpp>
#include <fstream>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "fploc/adapters/point_cloud2_t.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/core/text_out.h"
#include "fploc/recording/cloud_to_scan.h"
#include "fploc/recording/ouster_packets.h"
#include "fploc/recording/recording.h"
#include "fploc/recording/ros_msgs.h"
#include "laser_encode.h"
#include "lcm_log.h"
#include "ouster_raw.h"
#include "scan_encode.h"
#include "laser_mounts.h"
#include "tf_tree.h"
#include "tum_track.h"
#include "fploc/runtime/cli_messages.h"

using namespace fploc;
using namespace fploc::rec;
using fploc::import::LcmLog;
using fploc::import::OusterRawWriter;
using fploc::import::TumTrack;

namespace {

enum class Kind { kNone, kOusterPackets, kOusterMetadata, kCloud, kImu, kLaser, kOdom, kTf };

Kind kind_of(const Connection& c) {
  if (c.encoding == Encoding::kOther) return Kind::kNone;
  const std::string& t = c.type;
  if (t == "ouster_ros/PacketMsg" || t == "ouster_sensor_msgs/PacketMsg") return Kind::kOusterPackets;
  if (t == "std_msgs/String" && c.topic.size() >= 8 && c.topic.compare(c.topic.size() - 8, 8, "metadata") == 0)
    return Kind::kOusterMetadata;
  if (t == "sensor_msgs/PointCloud2") return Kind::kCloud;
  if (t == "sensor_msgs/Imu") return Kind::kImu;
  if (t == "sensor_msgs/LaserScan") return Kind::kLaser;
  if (t == "nav_msgs/Odometry") return Kind::kOdom;
  if (t == "tf2_msgs/TFMessage" || t == "tf/tfMessage") return Kind::kTf;
  return Kind::kNone;
}

std::string sanitize(const std::string& topic) {
  std::string s;
  for (char ch : topic) s += std::isalnum(uint8_t(ch)) ? char(std::toupper(uint8_t(ch))) : '_';
  while (!s.empty() && s[0] == '_') s.erase(0, 1);
  return s;
}

double seconds(int64_t ns) { return double(ns) * 1e-9; }

// Why a metadata topic's text is unusable: where its JSON stops parsing, or (valid JSON) what the OS-1 parser said.
std::string metadata_problem(const std::string& text, const std::string& err) {
  try {
    (void)nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    char b[8] = "";
    if (e.byte >= 1 && e.byte <= text.size()) std::snprintf(b, sizeof b, "0x%02x", unsigned(uint8_t(text[e.byte - 1])));
    return "its JSON (" + std::to_string(text.size()) + " B) does not parse at byte " + std::to_string(e.byte) + (*b ? std::string(" (") + b + ")" : "");
  } catch (const std::exception&) {
  }
  return "its JSON is not usable sensor metadata";
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The summary: topic names, types and error messages come from the recording and may hold any bytes (a damaged
// file, a control character). As JSON each byte that is not UTF-8 becomes U+FFFD (nlohmann's dump() threw on them,
// an abort); as text (the summary, --list, the errors) names are printed with \xHH escapes (fploc/core/text_out.h).
std::string dump_json(const nlohmann::json& j) { return json_text(j, 2); }

// Where the planar lasers sit (laser_mounts.h): tf kept at most every 100 ms per edge (a sample equal to the edge's
// last one is not kept: a static edge published again and again is one sample), each laser's frame from its first
// scan, the odometry's robot frame.
constexpr int64_t kMountTfGapNs = 100'000'000;
struct LaserSurvey {
  std::vector<std::string> topics;              // in the order of their first scan
  std::map<std::string, std::string> frame;     // topic -> header.frame_id of its first scan
  std::string odom_child;                       // the first odometry message's child_frame_id
  fploc::import::TfTree tf{kMountTfGapNs};
  void laser(const std::string& topic, const std::string& frame_id) {
    if (frame.emplace(topic, frame_id).second) topics.push_back(topic);
  }
  std::vector<fploc::import::LaserMount> mounts(const std::string& base_frame) {
    tf.sort();
    const std::string base = fploc::import::robot_frame(tf, base_frame.empty() ? odom_child : base_frame);
    std::vector<fploc::import::LaserMount> m;
    for (const auto& t : topics) m.push_back(fploc::import::laser_mount(tf, base, t, frame[t]));
    return m;
  }
};

// A first pass for the laser LASER_SCAN gets, when the recording has more than one: the whole file (a laser on a
// tilting unit may hold still for seconds first), given up at the first Ouster packet or point cloud (a 3D
// recording) and after kSurveyProbeS seconds of recording with fewer than two lasers seen (lasers scan at 5 Hz or
// more: one laser or none, no choice to make). False: no choice to make.
constexpr double kSurveyProbeS = 5;
bool survey_lasers(const std::string& path, const std::set<std::string>& wanted, LaserSurvey& s) {
  std::string err;
  auto rec = open_recording(path, &err);
  if (!rec) return false;
  RawMessage m;
  LaserScanView laser;
  Odometry odom;
  std::vector<Transform> ts;
  int64_t first_ns = INT64_MIN;
  while (rec->next(m)) {
    if (first_ns == INT64_MIN) first_ns = m.time_ns;
    if (s.topics.size() < 2 && seconds(m.time_ns) - seconds(first_ns) > kSurveyProbeS) return false;
    const Connection& c = rec->connections().at(m.conn);
    const Kind k = kind_of(c);
    if (k == Kind::kOusterPackets || k == Kind::kCloud) return false;
    if (k == Kind::kTf) {
      if (decode_tf(m.data, m.size, c.encoding, ts, &err))
        for (const auto& t : ts) s.tf.add(t);
    } else if (!wanted.empty() && !wanted.count(c.topic)) {
    } else if (k == Kind::kLaser && !s.frame.count(c.topic) && decode(m.data, m.size, c.encoding, laser, &err)) {
      s.laser(c.topic, laser.header.frame_id);
    } else if (k == Kind::kOdom && s.odom_child.empty() && decode(m.data, m.size, c.encoding, odom, &err)) {
      s.odom_child = odom.pose.child_frame_id;
    }
  }
  return s.topics.size() > 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc import: ROS 1 bags, ROS 2 MCAP and sqlite3 (.db3) recordings -> LCM log (and a TUM trajectory)"};
  fploc::rt::install_cli_messages(app, "fploc import");
  std::string path, out, tum_out, tf_parent, tf_child, odom_topic, metadata_file;
  std::vector<std::string> topics, channels;
  bool list = false, json = false, quiet = false, decode_ouster = false;
  double start = -1, end = -1;
  CloudOptions cloud_opt;
  app.add_option("recording", path, "ROS 1 bag (.bag), MCAP (.mcap), ROS 2 sqlite3 bag (.db3 file or rosbag2 bag folder)")->required();
  app.footer("Exit status: 0 everything imported; 1 the file is damaged or cut short, or Ouster lidar packets could not be\n"
             "written or have no usable metadata (the log holds everything before the damage); 2 bad arguments; 3 single messages did not decode\n"
             "and were skipped (the log holds all the others; stderr names each topic, the count and where the first is).");
  app.add_flag("--list", list, "print topics, types, message counts and the duration; write nothing");
  app.add_flag("--json", json, "machine-readable summary on stdout");
  app.add_option("--out", out, "LCM log to write");
  app.add_option("--topics", topics, "import only these topics (comma separated or repeated)")->delimiter(',');
  auto* start_opt = app.add_option("--start", start, "skip messages before START seconds after the first message");
  auto* end_opt = app.add_option("--end", end, "stop at END seconds after the first message");
  app.add_option("--metadata", metadata_file, "Ouster sensor metadata JSON (when the recording has no metadata topic)");
  app.add_flag("--decode", decode_ouster,
               "decode here: Ouster packets -> scan_t (OS1_SCAN) and imu_t (OS1_IMU), PointCloud2 -> scan_t (OS1_SCAN), "
               "instead of the packets for the drivers and the clouds for the cloud-to-scan node");
  app.add_option("--channel", channels, "TOPIC=CHANNEL: the LCM channel of a topic")->delimiter(',');
  app.add_option("--rings", cloud_opt.rings, "PointCloud2 without ring field: the number of rings (default: elevation gaps)");
  app.add_option("--columns", cloud_opt.columns, "PointCloud2: columns of the range image (default: organised width or most points per ring)");
  app.add_option("--tum-out", tum_out, "write a trajectory (TUM) from tf or an Odometry topic");
  app.add_option("--tf-parent", tf_parent, "with --tum-out: the tf parent frame (e.g. map, odom)");
  app.add_option("--tf-child", tf_child, "with --tum-out: the tf child frame (e.g. base_link)");
  app.add_option("--odom-topic", odom_topic, "with --tum-out: the nav_msgs/Odometry topic (default: the first one)");
  std::string base_frame;
  app.add_option("--base-frame", base_frame,
                 "the robot frame the lasers' mounts are given in (tf; default: the odometry's child frame, else "
                 "base_link, else base_footprint)");
  app.add_flag("--quiet", quiet, "no progress on stderr");
  bool direct_io = false;
  app.add_flag("--direct-io", direct_io,
               "write the log with O_DIRECT (not through the page cache; the same bytes; the page cache where the file "
               "system refuses it)");
  CLI11_PARSE(app, argc, argv);
  if (!list && out.empty() && tum_out.empty()) {
    std::cerr << "fploc import: give --list, --out LOG.lcm or --tum-out FILE\n";
    return 2;
  }
  // Seconds >= 0, END not before START: a NaN or negative one was ignored, an END before START imported nothing.
  for (auto [opt, v] : {std::pair{start_opt, start}, std::pair{end_opt, end}})
    if (opt->count() && !(std::isfinite(v) && v >= 0)) {
      std::cerr << "fploc import: " << opt->get_name() << " " << v << ": expected seconds >= 0\n";
      return 2;
    }
  if (start_opt->count() && end_opt->count() && end < start) {
    std::cerr << "fploc import: --end " << end << " is before --start " << start << "\n";
    return 2;
  }
  if (!tum_out.empty() && (tf_parent.empty() != tf_child.empty())) {
    std::cerr << "fploc import: --tf-parent and --tf-child go together\n";
    return 2;
  }

  std::string err;
  auto rec = open_recording(path, &err);
  if (!rec) {
    std::cerr << "fploc import: " << err << "\n";
    return 1;
  }

  // tf goes to the TUM file only (--tum-out with --tf-parent/--tf-child); otherwise the import says "not imported".
  const bool tf_imported = !tum_out.empty() && !tf_parent.empty();
  auto imported = [&](Kind k) { return k == Kind::kTf ? tf_imported : k != Kind::kNone; };
  static const char* kTfNote = "to TUM with --tum-out F --tf-parent P --tf-child C";
  if (list) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto topics_seen = summarize(*rec);
    int64_t first = INT64_MAX, last = INT64_MIN;
    uint64_t total = 0;
    for (const auto& [t, s] : topics_seen)
      if (s.count) {
        first = std::min(first, s.first_ns);
        last = std::max(last, s.last_ns);
        total += s.count;
      }
    const double dur = total ? seconds(last) - seconds(first) : 0.0;
    if (json) {
      nlohmann::json j;
      j["file"] = path;
      j["format"] = rec->format();
      j["messages"] = total;
      j["duration_s"] = dur;
      j["start_s"] = total ? seconds(first) : 0.0;
      j["error"] = rec->error();
      for (const auto& [t, s] : topics_seen) {
        Kind k = Kind::kNone;
        for (const auto& [id, c] : rec->connections())
          if (c.topic == t) k = kind_of(c);
        j["topics"][t] = {{"type", s.type}, {"count", s.count}, {"imported_as", imported(k) ? "yes" : ""}};
        if (k == Kind::kTf && !imported(k)) j["topics"][t]["note"] = kTfNote;
      }
      std::cout << dump_json(j) << "\n";
    } else {
      std::printf("%s: %s, %llu messages, %.3f s", printable(path).c_str(), rec->format().c_str(), (unsigned long long)total, dur);
      if (total) std::printf(" (from %.3f)", seconds(first));
      std::printf("\n");
      size_t w = 5;
      for (const auto& [t, s] : topics_seen) w = std::max(w, printable(t).size());
      for (const auto& [t, s] : topics_seen) {
        Connection c;
        for (const auto& [id, cc] : rec->connections())
          if (cc.topic == t) c = cc;
        const Kind k = kind_of(c);
        std::printf("  %-*s %8llu  %s%s\n", int(w), printable(t).c_str(), (unsigned long long)s.count, printable(s.type).c_str(),
                    imported(k) ? "  (imported)" : k == Kind::kTf ? (std::string("  (") + kTfNote + ")").c_str() : "");
      }
    }
    (void)t0;
    if (!rec->error().empty()) {
      std::cerr << "fploc import: " << rec->error() << "\n";
      return 1;
    }
    return 0;
  }

  // Channels: defaults by kind, unique per topic.
  std::map<std::string, std::string> channel_override;
  for (const auto& c : channels) {
    const auto k = c.find('=');
    if (k == std::string::npos) {
      std::cerr << "fploc import: --channel wants TOPIC=CHANNEL, got '" << c << "'\n";
      return 2;
    }
    channel_override[c.substr(0, k)] = c.substr(k + 1);
  }
  const std::set<std::string> wanted(topics.begin(), topics.end());
  std::map<uint32_t, std::string> channel_of;  // connection -> LCM channel
  std::map<std::string, std::string> topic_channel;
  // A channel named by --channel is not also a default: another topic of the same kind gets the suffixed name
  // (e.g. --channel /scan_front=LASER_SCAN puts a second laser on LASER_SCAN_SCAN_BACK, not on LASER_SCAN too).
  std::set<std::string> used_channels;
  for (const auto& [topic, ch] : channel_override) used_channels.insert(ch);
  auto channel_for = [&](const Connection& c, Kind k) -> const std::string& {
    auto it = channel_of.find(c.id);
    if (it != channel_of.end()) return it->second;
    std::string ch;
    auto ov = channel_override.find(c.topic);
    if (ov != channel_override.end()) {
      ch = ov->second;
    } else if (topic_channel.count(c.topic)) {
      ch = topic_channel[c.topic];
    } else {
      const std::string base = k == Kind::kLaser ? "LASER_SCAN"
                               : k == Kind::kOdom ? "WHEEL_ODOM"
                               : k == Kind::kImu ? "OS1_IMU"
                               : (k == Kind::kCloud && !decode_ouster) ? "POINT_CLOUD"
                                                                       : "OS1_SCAN";
      ch = used_channels.count(base) ? base + "_" + sanitize(c.topic) : base;
    }
    used_channels.insert(ch);
    topic_channel[c.topic] = ch;
    return channel_of[c.id] = ch;
  };

  // Options that name something in the recording (topics, tf frames, a start time) are checked before anything is
  // written: a name that matches nothing gave an empty or partial log and exit 0. A first pass reads until every
  // name has been seen (usually the first chunk; to the end only when one is wrong, to list the real ones).
  {
    std::set<std::string> named(topics.begin(), topics.end());
    for (const auto& [t, ch] : channel_override) named.insert(t);
    if (!odom_topic.empty()) named.insert(odom_topic);
    const bool frames_wanted = !tum_out.empty() && !tf_parent.empty();
    const bool start_wanted = start_opt->count() > 0;
    if (!named.empty() || frames_wanted || start_wanted) {
      auto pre = open_recording(path, &err);
      if (!pre) {
        std::cerr << "fploc import: " << err << "\n";
        return 1;
      }
      auto bare = [](const std::string& f) { return f.rfind('/', 0) == 0 ? f.substr(1) : f; };  // tf: leading '/' ignored
      std::set<std::string> frames;
      std::map<std::string, std::string> types;  // topic -> type
      int64_t first = INT64_MIN, last = INT64_MIN;
      bool start_seen = false;
      std::vector<Transform> ts;
      auto done = [&] {
        for (const auto& t : named)
          if (!types.count(t)) return false;
        if (frames_wanted && !(frames.count(bare(tf_parent)) && frames.count(bare(tf_child)))) return false;
        return !start_wanted || start_seen;
      };
      RawMessage pm;
      while (!done() && pre->next(pm)) {
        if (first == INT64_MIN) first = pm.time_ns;
        last = std::max(last, pm.time_ns);
        if (start_wanted && seconds(pm.time_ns) - seconds(first) >= start) start_seen = true;
        for (const auto& [id, c] : pre->connections()) types.emplace(c.topic, c.type);
        const Connection& c = pre->connections().at(pm.conn);
        if (frames_wanted && kind_of(c) == Kind::kTf && decode_tf(pm.data, pm.size, c.encoding, ts, &err))
          for (const auto& t : ts) frames.insert(bare(t.header.frame_id)), frames.insert(bare(t.child_frame_id));
      }
      for (const auto& [id, c] : pre->connections()) types.emplace(c.topic, c.type);
      std::vector<std::string> problems;
      for (const auto& t : named)
        if (!types.count(t)) problems.push_back("no topic '" + printable(t) + "' in the recording");
      if (!problems.empty()) {
        std::string list;
        for (const auto& [t, ty] : types) list += "\n  " + printable(t) + "  " + printable(ty);
        problems.back() += "; its topics:" + (list.empty() ? std::string(" none") : list);
      }
      if (frames_wanted)
        for (const auto& f : {tf_parent, tf_child})
          if (!frames.count(bare(f))) {
            std::string list;
            for (const auto& x : frames) list += (list.empty() ? "" : ", ") + printable(x);
            problems.push_back("no tf frame '" + printable(f) + "' in the recording's tf messages; its frames: " + (list.empty() ? "none" : list));
          }
      if (start_wanted && !start_seen) {
        char b[160];
        std::snprintf(b, sizeof b, "--start %g s is past the recording's end: its messages span 0 to %.3f s after the first", start,
                      first == INT64_MIN ? 0.0 : seconds(last) - seconds(first));
        problems.push_back(b);
      }
      if (!problems.empty()) {
        for (const auto& p : problems) std::cerr << "fploc import: " << p << "\n";
        if (!pre->error().empty()) std::cerr << "fploc import: (read up to the damage: " << pre->error() << ")\n";
        std::cerr << "fploc import: nothing written\n";
        return 2;
      }
    }
  }

  // More than one laser and no --channel for LASER_SCAN: the 2D mode's channel goes to the first laser whose scan
  // plane tf shows level all through the recording (a laser on a tilting unit, or one mounted askew, is no planar
  // scanner), the others to LASER_SCAN_<TOPIC>.
  std::string laser_choice;  // what was chosen and why (printed with the summary)
  LaserSurvey pre;            // the whole recording's lasers (else the mounts come from what the import read)
  std::vector<fploc::import::LaserMount> pre_mounts;
  if (!used_channels.count("LASER_SCAN") && survey_lasers(path, wanted, pre)) {
    pre_mounts = pre.mounts(base_frame);
    std::string not_level;
    for (const auto& m : pre_mounts) {
      if (channel_override.count(m.topic)) continue;  // the user named its channel
      if (!m.level()) {
        not_level += (not_level.empty() ? "" : ", ") + printable(m.topic);
        continue;
      }
      topic_channel[m.topic] = "LASER_SCAN";  // explicitly: with --start the main pass may meet another laser first
      used_channels.insert("LASER_SCAN");
      laser_choice = "LASER_SCAN is " + printable(m.topic) + ", the first laser tf shows level" +
                     (not_level.empty() ? std::string() : " (not level: " + not_level + ")");
      break;
    }
  }

  LcmLog lcm_log;
  if (!out.empty() && !lcm_log.open(out, direct_io)) {
    std::cerr << "fploc import: cannot write " << printable(out) << "\n";
    return 1;
  }
  TumTrack tum;
  if (!tum_out.empty() && !tum.open(tum_out, tf_parent, tf_child)) {
    std::cerr << "fploc import: cannot write " << printable(tum_out) << "\n";
    return 1;
  }

  OusterPackets ouster;
  OusterRawWriter raw(out.empty() ? nullptr : &lcm_log);
  std::string metadata_text;  // --metadata, written (packets mode) with the first Ouster packet's time
  if (!metadata_file.empty()) {
    std::ifstream in(metadata_file);
    std::stringstream ss;
    ss << in.rdbuf();
    metadata_text = ss.str();
    if (!in || !(decode_ouster ? ouster.set_metadata(metadata_text, metadata_file, &err)
                               : OusterRawWriter(nullptr).metadata(metadata_text, metadata_file, 0, &err))) {
      std::cerr << "fploc import: " << (in ? err : metadata_file + ": cannot read") << "\n";
      return 1;
    }
  }
  std::string ouster_scan_channel = "OS1_SCAN", ouster_imu_channel = "OS1_IMU";
  std::map<std::string, uint64_t> written, skipped_types, decode_errors;
  std::map<std::string, std::string> first_decode_error;  // topic -> "WHERE: why" of its first undecodable message
  std::vector<Scan> frames;
  size_t frames_total = 0;
  struct FrameInfo { int32_t frame_id, height, width, missing; };
  std::vector<FrameInfo> frame_list;  // for the summary (the first 1000)
  std::map<std::string, int64_t> seq;
  CloudStats cstats;
  std::map<std::string, CloudStats> cloud_info;
  // Per topic, the converted clouds organised but with stray points (binned by azimuth) or relabelled ones.
  struct StrayTally { uint64_t clouds = 0, with = 0, stray = 0, relabelled = 0; int rings = 0; };
  std::map<std::string, StrayTally> stray_tally;
  auto tally = [&](const std::string& topic, const CloudStats& st) {
    auto& t = stray_tally[topic];
    ++t.clouds;
    if (!st.stray_points && !st.relabelled_points) return;
    ++t.with;
    t.stray += st.stray_points;
    t.relabelled += st.relabelled_points;
    t.rings = std::max(t.rings, st.azimuth_rings);
  };
  int64_t first_ns = INT64_MIN;
  const auto t_start = std::chrono::steady_clock::now();
  auto last_progress = t_start;
  uint64_t read_msgs = 0;

  auto emit_frames = [&](int64_t fallback_ns) {
    for (size_t i = 0; i < frames.size(); ++i) {
      Scan& s = frames[i];
      s.seq = seq[ouster_scan_channel]++;
      const int64_t t = i < ouster.frame_times_ns.size() ? ouster.frame_times_ns[i] : fallback_ns;
      if (frame_list.size() < 1000) frame_list.push_back({s.frame_id, s.height, s.width, s.missing_columns});
      if (!out.empty())
        if (uint8_t* p = lcm_log.begin_event(ouster_scan_channel, t / 1000, fploc::import::encoded_scan_size(s)))
          fploc::import::encode_scan(s, p);
      ++written[ouster_scan_channel];
    }
    frames_total += frames.size();
    for (auto& s : frames) ouster.recycle(std::move(s));  // the next frame reuses the buffers
    frames.clear();
    ouster.frame_times_ns.clear();
  };
  RawMessage m;
  auto bad = [&](const Connection& c, const std::string& e) {
    if (!decode_errors[c.topic]++) first_decode_error[c.topic] = where(m) + ": " + e;
  };

  std::string metadata_failed, metadata_why;  // the first metadata topic whose JSON was unusable, and why
  bool odom_chosen = !odom_topic.empty();
  Scan cloud_scan;
  std::vector<uint8_t> cloud_header;  // point_cloud2_t up to its data; the points follow from the recording
  std::map<std::string, std::string> cloud_check_error;  // topic -> why its first cloud does not convert
  LaserScanView laser;
  LaserSurvey survey;     // the lasers' frames and tf, for their mounts (laser_mounts.h)
  bool mount_tf = true;   // tf kept for them: until a 3D recording shows (an Ouster packet or a cloud before any scan)
  std::vector<Transform> mount_ts;
  while (rec->next(m)) {
    ++read_msgs;
    if (first_ns == INT64_MIN) first_ns = m.time_ns;
    const double rel = seconds(m.time_ns) - seconds(first_ns);
    if (end >= 0 && rel > end) break;
    const Connection& c = rec->connections().at(m.conn);
    const Kind k = kind_of(c);
    // tf for the mounts whatever --start and --topics keep (a latched /tf_static is recorded at the start).
    if (mount_tf && (k == Kind::kOusterPackets || k == Kind::kCloud) && survey.topics.empty()) mount_tf = false;
    bool tf_decoded = false;  // mount_ts holds this message's transforms (the TUM output takes them too)
    if (mount_tf && k == Kind::kTf && (tf_decoded = decode_tf(m.data, m.size, c.encoding, mount_ts, &err)))
      for (const auto& t : mount_ts) survey.tf.add(t);
    if (start >= 0 && rel < start) continue;
    if (!wanted.empty() && !wanted.count(c.topic)) continue;
    if (!quiet && (read_msgs & 15) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_progress > std::chrono::seconds(1)) {
        last_progress = now;
        std::fprintf(stderr, "\rfploc import: %5.1f%% (%.0f MB, %.1f s of recording)", 100.0 * rec->position() / std::max<uint64_t>(1, rec->size()),
                     rec->position() / 1e6, rel);
      }
    }
    switch (k) {
      case Kind::kNone: ++skipped_types[c.type]; break;
      case Kind::kOusterMetadata: {
        std::string text;
        if (!decode_string(m.data, m.size, c.encoding, text, &err)) { bad(c, err); break; }
        if (!(decode_ouster ? ouster.set_metadata(text, c.topic, &err) : raw.metadata(text, c.topic, m.time_ns, &err))) {
          bad(c, err);
          if (metadata_failed.empty()) metadata_failed = c.topic, metadata_why = metadata_problem(text, err) + ", the message at " + where(m);
          if (!decode_ouster) raw.without_metadata();  // the lidar packets are kept, as they are
        }
        ++written["(metadata " + c.topic + ")"];
        break;
      }
      case Kind::kOusterPackets: {
        const uint8_t* buf = nullptr;
        size_t n = 0;
        if (!decode_bytes(m.data, m.size, c.encoding, &buf, &n, &err)) { bad(c, err); break; }
        // The topic says what a packet is (a damaged IMU packet is not a lidar packet because of its size); a
        // topic named otherwise: its size.
        const auto route = ends_with(c.topic, "imu_packets")     ? OusterRawWriter::Route::kImu
                           : ends_with(c.topic, "lidar_packets") ? OusterRawWriter::Route::kLidar
                                                                 : OusterRawWriter::Route::kBySize;
        if (route == OusterRawWriter::Route::kImu && n != os1::kImuPacketSize) {
          bad(c, "IMU packet of " + std::to_string(n) + " B (an IMU packet has " + std::to_string(os1::kImuPacketSize) + ")");
          break;
        }
        if (!decode_ouster) {
          if (!raw.has_metadata() && !metadata_text.empty()) raw.metadata(metadata_text, metadata_file, m.time_ns, &err);
          raw.packet(buf, n, m.time_ns, rec->stable(buf, n), route);
          break;
        }
        if (route == OusterRawWriter::Route::kLidar && n == os1::kImuPacketSize) {  // the decoder would take it for IMU
          bad(c, "lidar packet of " + std::to_string(n) + " B (the size of an IMU packet)");
          break;
        }
        os1::ImuSample s;
        if (ouster.add(buf, n, m.time_ns, frames, &s)) {
          imu_t im{};
          im.utime = int64_t(s.accel_ts_ns / 1000);
          im.seq = seq[ouster_imu_channel]++;
          im.accel_utime = int64_t(s.accel_ts_ns / 1000);
          im.gyro_utime = int64_t(s.gyro_ts_ns / 1000);
          for (int i = 0; i < 3; ++i) im.accel[i] = s.accel_mps2[i], im.gyro[i] = s.gyro_radps[i];
          im.source = "os1";
          if (!out.empty()) lcm_log.write(ouster_imu_channel, m.time_ns / 1000, im);
          ++written[ouster_imu_channel];
        }
        emit_frames(m.time_ns);
        break;
      }
      case Kind::kCloud: {
        PointCloud2 pc;
        if (!decode(m.data, m.size, c.encoding, pc, &err)) { bad(c, err); break; }
        if (!decode_ouster) {
          // Kept as it is (point_cloud2_t); the cloud-to-scan node converts it on replay. The first cloud of
          // each topic is converted here once, to report its layout and to say now when it cannot be.
          const std::string& ch = channel_for(c, k);
          if (!cloud_info.count(c.topic)) {
            if (!cloud_to_scan(pc, cloud_opt, cloud_scan, &cstats, &err)) cloud_check_error[c.topic] = err;
            else tally(c.topic, cstats);
            cloud_info[c.topic] = cstats;
          }
          if (!out.empty()) {
            fploc::adapters::encode_without_data(pc, seq[ch], c.topic, cloud_header);
            lcm_log.write_parts(ch, m.time_ns / 1000, cloud_header.data(), cloud_header.size(), pc.data, pc.data_size,
                                rec->stable(pc.data, pc.data_size));
          }
          ++seq[ch];
          ++written[ch];
          break;
        }
        Scan& s = cloud_scan;  // buffers reused from cloud to cloud
        if (!cloud_to_scan(pc, cloud_opt, s, &cstats, &err)) { bad(c, err); break; }
        const std::string& ch = channel_for(c, k);
        s.seq = seq[ch]++;
        s.frame_id = int32_t(s.seq & 0xFFFF);
        s.sensor = "PointCloud2 " + c.topic + " (" + std::to_string(s.height) + " rings)";
        cloud_info[c.topic] = cstats;
        tally(c.topic, cstats);
        if (!out.empty())
          if (uint8_t* p = lcm_log.begin_event(ch, m.time_ns / 1000, fploc::import::encoded_scan_size(s)))
            fploc::import::encode_scan(s, p);
        ++written[ch];
        break;
      }
      case Kind::kImu: {
        Imu u;
        if (!decode(m.data, m.size, c.encoding, u, &err)) { bad(c, err); break; }
        const std::string& ch = channel_for(c, k);
        imu_t im{};
        im.utime = im.accel_utime = im.gyro_utime = u.header.stamp_ns / 1000;
        im.seq = seq[ch]++;
        for (int i = 0; i < 3; ++i) im.accel[i] = u.linear_acceleration[i], im.gyro[i] = u.angular_velocity[i];
        im.source = "ros " + c.topic;
        if (!out.empty()) lcm_log.write(ch, m.time_ns / 1000, im);
        ++written[ch];
        break;
      }
      case Kind::kLaser: {
        // Encoded straight from the recording's bytes into the log's buffer (laser_encode.h): the bytes of
        // laser_scan_t::encode, in one pass.
        if (!decode(m.data, m.size, c.encoding, laser, &err)) { bad(c, err); break; }
        survey.laser(c.topic, laser.header.frame_id);
        const std::string& ch = channel_for(c, k);
        if (!out.empty()) {
          const size_t n = fploc::import::laser_scan_encoded_size(laser);
          if (uint8_t* p = lcm_log.begin_event(ch, m.time_ns / 1000, n)) fploc::import::encode_laser_scan(laser, p);
        }
        ++written[ch];
        break;
      }
      case Kind::kOdom: {
        Odometry o;
        if (!decode(m.data, m.size, c.encoding, o, &err)) { bad(c, err); break; }
        if (survey.odom_child.empty()) survey.odom_child = o.pose.child_frame_id;
        const std::string& ch = channel_for(c, k);
        pose_t p{};
        p.utime = o.pose.header.stamp_ns / 1000;
        p.seq = seq[ch]++;
        p.floor_index = -1;  // the odometry frame: no floor
        for (int i = 0; i < 3; ++i) p.position[i] = o.pose.t[size_t(i)];
        for (int i = 0; i < 4; ++i) p.orientation[i] = o.pose.q[size_t(i)];
        if (!out.empty()) lcm_log.write(ch, m.time_ns / 1000, p);
        ++written[ch];
        if (tum_out.empty() || !tf_parent.empty()) break;
        if (!odom_chosen) odom_topic = c.topic, odom_chosen = true;
        if (c.topic != odom_topic) break;
        tum.odometry(o);
        ++written["(tum " + c.topic + ")"];
        break;
      }
      case Kind::kTf: {
        if (tum_out.empty() || tf_parent.empty()) { ++skipped_types[c.type]; break; }
        if (!tf_decoded && !decode_tf(m.data, m.size, c.encoding, mount_ts, &err)) { bad(c, err); break; }
        for (const auto& t : mount_ts) tum.tf(t);
        ++written["(tf " + c.topic + ")"];
        break;
      }
    }
  }
  ouster.flush(frames);
  emit_frames(m.time_ns);
  if (!quiet && std::chrono::steady_clock::now() - t_start > std::chrono::seconds(1)) std::fprintf(stderr, "\n");
  const bool log_direct = lcm_log.direct();
  const bool log_ok = lcm_log.close();
  tum.close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();

  std::vector<std::string> problems;
  if (!log_ok) problems.push_back(printable(out) + ": writing failed (disk full?); the log is cut short");
  if (!rec->error().empty()) problems.push_back(rec->error() + " (the output holds everything before it)");
  // Messages that did not decode are skipped, the others written: exit 3 (the log is complete but for them).
  // Lidar packets without metadata because the metadata topic's JSON is unusable: one line for both (below).
  const uint64_t lidar_without = decode_ouster ? ouster.lidar_packets : raw.lidar_packets;
  const bool metadata_broken = !metadata_failed.empty() && lidar_without > 0 && !(decode_ouster ? ouster.has_metadata() : raw.has_metadata());
  for (const auto& [t, n] : decode_errors)
    if (!(metadata_broken && t == metadata_failed))
      problems.push_back(printable(t) + ": " + std::to_string(n) + " message" + (n > 1 ? "s" : "") + " not decoded, skipped (the first at " +
                       first_decode_error[t] + ")");
  // Lidar packets that could not be written (no metadata to decode them, or too many before it): the log lacks
  // the lidar, so the import failed (exit 1), as for a damaged file.
  const bool lidar_lost = (ouster.lidar_packets > 0 && !ouster.has_metadata()) ||
                          (raw.lidar_packets > 0 && !raw.has_metadata()) || raw.waiting_dropped > 0;
  if (metadata_broken)
    problems.push_back(printable(metadata_failed) + ": the metadata topic is there but " + metadata_why + "; " + std::to_string(lidar_without) +
                       " Ouster lidar packets " +
                       (decode_ouster ? "could not be decoded: give --metadata FILE"
                                      : "written as they are, without metadata: give --metadata FILE (to import again, or "
                                        "--set os1_driver.metadata=FILE on replay)"));
  else if (ouster.lidar_packets > 0 && !ouster.has_metadata())
    problems.push_back(std::to_string(ouster.lidar_packets) + " Ouster lidar packets without metadata (no metadata topic; give --metadata FILE)");
  else if (raw.lidar_packets > 0 && !raw.has_metadata())
    problems.push_back(std::to_string(raw.lidar_packets) + " Ouster lidar packets without metadata (no metadata topic; give --metadata FILE)");
  if (raw.waiting_dropped)
    problems.push_back(std::to_string(raw.waiting_dropped) + " Ouster lidar packets before the metadata dropped (more than 20000 waited)");
  if (raw.other_size)
    problems.push_back(std::to_string(raw.other_size) + " Ouster lidar packets not of the metadata's size " + std::to_string(raw.lidar_size()) +
                       " B (written as they are; the driver will report them)");
  if (raw.imu_packets) written[raw.imu_channel] = raw.imu_packets;  // IMU packets need no metadata
  if (raw.written_without_metadata) written[raw.lidar_channel] = raw.written_without_metadata;
  if (raw.lidar_packets && raw.has_metadata()) {
    written[raw.lidar_channel] = raw.lidar_packets - raw.waiting_dropped;
    written[raw.metadata_channel] = 1;
  }
  // The graph that replays what was written: the drivers' one for packets, the pipeline for scans.
  std::string replay_graph;
  for (const auto& [ch, n] : written) {
    if (!n) continue;
    if (ch == raw.lidar_channel) replay_graph = "graphs/replay-packets.pbtxt";
  }
  for (const auto& [ch, n] : written)
    if (n && ch.rfind("POINT_CLOUD", 0) == 0 && replay_graph.empty()) replay_graph = "graphs/replay-clouds.pbtxt";
  for (const auto& [ch, n] : written)
    if (n && ch.rfind("OS1_SCAN", 0) == 0 && replay_graph.empty()) replay_graph = "graphs/replay.pbtxt";
  if (replay_graph.empty())
    for (const auto& [ch, n] : written)
      if (n && ch.rfind("LASER_SCAN", 0) == 0) replay_graph = "graphs/lidar2d.pbtxt";
  for (const auto& [t, e] : cloud_check_error)
    problems.push_back(printable(t) + ": its first cloud does not convert to a range image (" + e +
                       "); the clouds are written as they are, the cloud-to-scan node will report the same on replay");
  if (ouster.bad_packets) problems.push_back(std::to_string(ouster.bad_packets) + " bad Ouster packets skipped; last: " + ouster.last_error);
  const bool skipped = !decode_errors.empty() || ouster.bad_packets > 0;
  // The lasers' mounts (tf), and the one on LASER_SCAN (what the 2D mode reads).
  const auto mounts = !pre_mounts.empty()     ? pre_mounts
                      : survey.topics.empty() ? std::vector<fploc::import::LaserMount>{}
                                              : survey.mounts(base_frame);
  const fploc::import::LaserMount* main_laser = nullptr;
  for (const auto& lm : mounts)
    if (topic_channel.count(lm.topic) && topic_channel[lm.topic] == "LASER_SCAN") main_laser = &lm;
  std::vector<std::string> warnings;
  if (main_laser && main_laser->found && !main_laser->level())
    warnings.push_back("LASER_SCAN (" + printable(main_laser->topic) + ") " + main_laser->describe() +
                       "; give a level laser with --channel TOPIC=LASER_SCAN");
  for (const auto& [t, tl] : stray_tally)
    if (tl.with) {
      std::string w = "cloud " + printable(t) + ": " + std::to_string(tl.with) + " of " + std::to_string(tl.clouds) +
                      (decode_ouster ? " clouds" : " cloud (the first)") + " organised with stray points: " +
                      std::to_string(tl.stray) + " points binned by azimuth (off their ring's row, more than a column "
                      "off its shift" + (tl.rings ? ", or of a ring binned whole: up to " + std::to_string(tl.rings) +
                      (tl.rings == 1 ? " ring" : " rings") + " a cloud" : std::string()) + ")";
      if (tl.relabelled)
        w += ", " + std::to_string(tl.relabelled) + " points with a ring value no row has taken as their row's ring";
      warnings.push_back(w + "; the other points keep their columns");
    }

  if (json) {
    nlohmann::json j;
    j["file"] = path;
    j["format"] = rec->format();
    j["messages_read"] = read_msgs;
    j["written"] = written;
    j["skipped_types"] = skipped_types;
    j["channels"] = topic_channel;
    j["seconds"] = wall;
    j["events"] = lcm_log.events();
    j["direct_io"] = log_direct;
    j["replay_graph"] = replay_graph;
    if (raw.has_metadata() && raw.lidar_packets + raw.imu_packets > 0)
      j["ouster"] = {{"mode", "packets"}, {"sensor", raw.sensor}, {"pixels_per_column", raw.pixels_per_column},
                     {"columns_per_frame", raw.columns_per_frame}, {"udp_profile", raw.udp_profile},
                     {"lidar_packets", raw.lidar_packets}, {"imu_packets", raw.imu_packets}};
    if (ouster.info()) {
      j["ouster"] = {{"mode", "scans"}, {"sensor", ouster.info()->sensor_name()}, {"pixels_per_column", ouster.info()->pixels_per_column},
                     {"columns_per_frame", ouster.info()->columns_per_frame}, {"udp_profile", os1::to_string(ouster.info()->profile)},
                     {"lidar_packets", ouster.lidar_packets}, {"imu_packets", ouster.imu_packets}, {"frames", frames_total}};
      nlohmann::json fr = nlohmann::json::array();
      for (const auto& s : frame_list) fr.push_back({{"frame_id", s.frame_id}, {"height", s.height}, {"width", s.width}, {"missing_columns", s.missing}});
      j["ouster"]["frame_list"] = fr;
    }
    for (const auto& [t, s] : cloud_info)
      j["clouds"][t] = {{"mode", decode_ouster ? "scans" : "clouds"}, {"ring_source", s.ring_source}, {"time_source", s.time_source}, {"points", s.points}, {"kept", s.kept},
                        {"collisions", s.collisions}, {"max_azimuth_error_deg", s.max_azimuth_error_deg},
                        {"column_source", s.column_source}, {"zero_range", s.zero_range}, {"not_finite", s.not_finite},
                        {"too_far", s.too_far}, {"stray_points", s.stray_points}, {"azimuth_rings", s.azimuth_rings},
                        {"relabelled_points", s.relabelled_points},
                        {"clouds_with_stray_points", stray_tally.count(t) ? stray_tally[t].with : 0}};
    for (const auto& lm : mounts) {
      nlohmann::json l = {{"frame", lm.frame}, {"channel", topic_channel.count(lm.topic) ? topic_channel[lm.topic] : ""},
                          {"mount_found", lm.found}};
      if (lm.found)
        l.update({{"base_frame", lm.base}, {"x_m", lm.x_m}, {"y_m", lm.y_m}, {"z_m", lm.z_m}, {"yaw_deg", lm.yaw_deg},
                  {"upside_down", lm.upside_down}, {"tilt_min_deg", lm.tilt_min_deg}, {"tilt_max_deg", lm.tilt_max_deg},
                  {"level", lm.level()}});
      else
        l["why"] = lm.why;
      j["lasers"][lm.topic] = l;
    }
    if (!laser_choice.empty()) j["laser_choice"] = laser_choice;
    j["warnings"] = warnings;
    j["errors"] = problems;
    for (const auto& [t, n] : decode_errors) j["not_decoded"][t] = {{"count", n}, {"first", first_decode_error[t]}};
    std::cout << dump_json(j) << "\n";
  } else {
    std::printf("%s (%s): %llu messages read in %.2f s\n", printable(path).c_str(), rec->format().c_str(), (unsigned long long)read_msgs, wall);
    int width = 28;  // the channel column as wide as the longest name (long ones broke the column)
    for (const auto& [ch, n] : written) width = std::max(width, int(printable(ch).size()));
    for (const auto& [ch, n] : written) std::printf("  %-*s %8llu\n", width, printable(ch).c_str(), (unsigned long long)n);
    for (const auto& [t, ch] : topic_channel) std::printf("  topic %s -> %s\n", printable(t).c_str(), printable(ch).c_str());
    for (const auto& lm : mounts)
      std::printf("  laser %s (frame %s): %s\n", printable(lm.topic).c_str(), printable(lm.frame).c_str(), lm.describe().c_str());
    if (!laser_choice.empty()) std::printf("  %s\n", laser_choice.c_str());
    if (raw.has_metadata() && raw.lidar_packets + raw.imu_packets > 0)
      std::printf("  ouster: %s, %dx%d (%s), %llu lidar + %llu imu packets written as they are\n"
                  "          (the OS-1 and IMU drivers decode them on replay; --decode writes scan_t and imu_t here)\n",
                  printable(raw.sensor).c_str(), raw.pixels_per_column, raw.columns_per_frame, raw.udp_profile.c_str(),
                  (unsigned long long)raw.lidar_packets, (unsigned long long)raw.imu_packets);
    if (ouster.info())
      std::printf("  ouster: %s, %dx%d (%s), %llu lidar + %llu imu packets -> %zu frames\n", printable(ouster.info()->sensor_name()).c_str(),
                  ouster.info()->pixels_per_column, ouster.info()->columns_per_frame, os1::to_string(ouster.info()->profile),
                  (unsigned long long)ouster.lidar_packets, (unsigned long long)ouster.imu_packets, frames_total);
    for (const auto& [t, s] : cloud_info) {
      // What became of the points, in words: the range image holds one point per pixel (ring, column).
      std::string lost;
      auto add = [&](uint64_t n, const char* what) {
        if (n) lost += (lost.empty() ? "" : ", ") + std::to_string(n) + " " + what;
      };
      add(s.zero_range, "without a return (range 0)");
      add(s.not_finite, "with a NaN/inf coordinate");
      add(s.too_far, "beyond 2000 m");
      add(s.collisions, s.collisions == 1 ? "in a pixel another point holds (a collision: the nearer of the two kept)"
                                          : "in a pixel another point holds (collisions: the nearer of two kept)");
      std::printf("  cloud %s%s: rings from %s, columns from %s, times from %s; %llu/%llu points kept in the range image%s%s%s\n",
                  printable(t).c_str(), decode_ouster ? "" : " (first cloud)", s.ring_source.c_str(),
                  s.column_source == "organised" ? "the organised cloud's columns (one point per pixel)" : "the azimuths",
                  s.time_source.c_str(), (unsigned long long)s.kept, (unsigned long long)s.points, lost.empty() ? "" : " (not kept: ",
                  lost.c_str(), lost.empty() ? "" : ")");
      if (s.collisions)
        std::printf("          a collision loses the farther of two points that fall in one pixel: %.2f %% of the points here%s\n",
                    100.0 * double(s.collisions) / double(std::max<uint64_t>(1, s.points)),
                    s.collisions * 100 < s.points ? " (a few lost points: harmless for the localization)"
                                                  : " (many: give --columns W, or --rings N, to match the sensor)");
    }
    if (!decode_ouster && !cloud_info.empty())
      std::printf("  clouds written as they are (point_cloud2_t); the cloud-to-scan node converts them on replay\n"
                  "          (--set cloud_to_scan.rings=N / cloud_to_scan.columns=W there; --decode converts here)\n");
    if (!skipped_types.empty()) {
      std::printf("  not imported:");
      for (const auto& [t, n] : skipped_types) std::printf(" %s (%llu)", printable(t).c_str(), (unsigned long long)n);
      std::printf("\n");
    }
    if (!out.empty() && !replay_graph.empty()) {
      // The whole command: where the poses go (--out; else ./poses.tum, silently) and the plan and start pose of each
      // localizing node as placeholders (else the graph's own: the demo room's plan). PLAN and X Y YAW (radians) are
      // the user's to fill in.
      const bool lidar2d = replay_graph == "graphs/lidar2d.pbtxt";
      const std::vector<std::string> plan_nodes = lidar2d ? std::vector<std::string>{"matcher", "optimizer", "grid2d", "amcl"}
                                                          : std::vector<std::string>{"matcher", "optimizer", "relocalizer"};
      const std::vector<std::string> pose_nodes = lidar2d ? std::vector<std::string>{"matcher", "grid2d", "amcl"}
                                                          : std::vector<std::string>{"matcher"};
      std::string est = std::filesystem::path(out).replace_extension("").string() + "-poses.tum";
      // Without a start (not for lidar2d: grid2d searches by itself without grid2d.initial_pose), the relocalizer searches.
      std::printf("  replay (PLAN: your plan; X Y: the start in it [m], YAW [rad]%s):\n"
                  "    bin/fploc replay --graph %s --log %s --out %s \\\n     ", lidar2d ? "" : "; no start known: --set matcher.wait_for_initial_pose=true instead, the relocalizer searches the plan",
                  replay_graph.c_str(), printable(out).c_str(), printable(est).c_str());
      for (const auto& n : plan_nodes) std::printf(" --set %s.plan.file=PLAN", n.c_str());
      std::printf(" \\\n     ");
      for (const auto& n : pose_nodes)
        std::printf(" --set %s.initial_pose.x=X --set %s.initial_pose.y=Y --set %s.initial_pose.yaw=YAW", n.c_str(), n.c_str(), n.c_str());
      if (lidar2d && main_laser && main_laser->found) {  // the laser's mount from tf, for both nodes that read the scans
        std::printf(" \\\n     ");
        for (const char* n : {"laser2d", "grid2d"}) {
          std::printf(" --set %s.mount_x_m=%.3f --set %s.mount_y_m=%.3f --set %s.mount_yaw_deg=%.1f", n, main_laser->x_m, n,
                      main_laser->y_m, n, main_laser->yaw_deg);
          if (main_laser->upside_down) std::printf(" --set %s.upside_down=true", n);
        }
      }
      std::printf("\n");
    }
    if (!tum_out.empty()) std::printf("  %s: %llu poses\n", printable(tum_out).c_str(), (unsigned long long)tum.poses());
  }
  for (const auto& w : warnings) std::cerr << "fploc import: warning: " << w << "\n";
  for (const auto& p : problems) std::cerr << "fploc import: " << p << "\n";
  if (!(rec->error().empty() && log_ok && !lidar_lost)) return 1;
  if (skipped) {
    std::cerr << "fploc import: exit 3: messages were skipped (above); the log holds everything else\n";
    return 3;
  }
  return 0;
}
