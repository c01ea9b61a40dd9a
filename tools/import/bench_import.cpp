// fploc bench import [--size-mb 1024] [--kind ouster|cloud|laser|all] [--format bag|mcap]
//                    [--compression none|lz4|bz2|zstd] [--runs 3] [--json] [--keep DIR] [--baseline-importer EXE] [--direct-io]
// Import speed as a ratio against `cat` of the same file, timed in the same run (target: <= 2x).
// Writes a large bag into a temp dir (deleted afterwards), by content:
//   ouster: the ouster_ros bag's packets (../shared/data/ouster/512x10_raw.bag; OS-0-128, 512x10,
//           RNG15_RFL8_NIR8) repeated with advancing frame ids and times; imported twice: as packets
//           (the default, "ouster") and decoded to scan_t frames ("ouster --decode")
//   cloud:  VLP-16-like sensor_msgs/PointCloud2 (16 x 1800 points, Velodyne field layout) -> scan_t
//   laser:  sensor_msgs/LaserScan (1081 beams with intensities, a Hokuyo UTM-30LX-like scan) -> laser_scan_t
// then times, --runs times each, interleaved: `cat BAG > /dev/null` (after one warm-up read, so both run
// from the page cache), `cat BAG > COPY` (read + write the same volume) and `fploc-import BAG --out
// LOG.lcm`; and again with the bag's pages evicted before each run (cold). Medians are reported.
// --format mcap writes an MCAP file instead (ROS 1 message encoding, the same messages; chunks none, zstd
// or lz4, with their CRC-32s and the data section's, as the MCAP libraries write them).
// Compressed files (--compression bz2|lz4|zstd): the same compressed chunks, concatenated into one file, are
// also decompressed by the compression's own tool (`bzip2 -dc`, `lz4 -dc`, `zstd -dc`; the same libraries),
// to /dev/null and into a file, in the same runs: the decompressor's speed on the same data, the bound
// an importer cannot beat (the `cat` ratio of a compressed bag includes all of the decompression).
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <map>
#include <utility>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fploc/core/text_out.h"
#include "fploc/recording/bag_writer.h"
#include "fploc/recording/mcap_writer.h"
#include "fploc/recording/recording.h"
#include "fploc/runtime/cli_messages.h"

using namespace fploc::rec;
namespace fs = std::filesystem;

namespace {

// CPU seconds of the finished children: user, system.
std::pair<double, double> children_cpu() {
  rusage u{};
  getrusage(RUSAGE_CHILDREN, &u);
  return {u.ru_utime.tv_sec + 1e-6 * u.ru_utime.tv_usec, u.ru_stime.tv_sec + 1e-6 * u.ru_stime.tv_usec};
}
double last_cpu = 0;  // CPU seconds (user + sys) of the last run(): what a busy shared machine does not inflate
double last_user = 0, last_sys = 0;  // the same, split

double run(const std::string& cmd) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto c0 = children_cpu();
  const int rc = std::system(cmd.c_str());
  const auto c1 = children_cpu();
  last_user = c1.first - c0.first, last_sys = c1.second - c0.second;
  last_cpu = last_user + last_sys;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rc != 0) {
    std::cerr << "fploc bench import: '" << cmd << "' failed (" << rc << ")\n";
    std::exit(1);
  }
  return s;
}

// Drops one file's pages from the page cache (after writing them back): the next read is a cold read
// from the disk. Only this file is affected.
void evict(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return;
  fdatasync(fd);
  posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  ::close(fd);
}

void put32(std::vector<uint8_t>& b, uint32_t v) { b.insert(b.end(), (uint8_t*)&v, (uint8_t*)&v + 4); }
void put_str(std::vector<uint8_t>& b, const std::string& s) {
  put32(b, uint32_t(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}

// std_msgs/Header (ROS 1): seq, stamp (patched per copy), frame_id.
std::vector<uint8_t> ros1_header(const std::string& frame) {
  std::vector<uint8_t> b;
  for (int i = 0; i < 3; ++i) put32(b, 0);
  put_str(b, frame);
  return b;
}

// Range from the origin along the unit direction d (2 or 3 components) to the walls of a 10 x 6 x 3.5 m room.
double room_range(const double* d, int dims) {
  double t = 1e9;
  const double lo[3] = {-4, -2.5, -1.5}, hi[3] = {6, 3.5, 2};
  for (int i = 0; i < dims; ++i) {
    if (d[i] > 1e-9) t = std::min(t, hi[i] / d[i]);
    if (d[i] < -1e-9) t = std::min(t, lo[i] / d[i]);
  }
  return t;
}

// ROS 1 PointCloud2 of a VLP-16 in a 10 x 6 m room (header stamp patched per copy at bytes 4..11).
std::vector<uint8_t> vlp16_cloud() {
  std::vector<uint8_t> b = ros1_header("velodyne");
  const int rings = 16, cols = 1800, step = 22;
  put32(b, 1);
  put32(b, uint32_t(rings * cols));
  const std::pair<const char*, std::pair<uint32_t, uint8_t>> f[] = {{"x", {0, 7}}, {"y", {4, 7}}, {"z", {8, 7}}, {"intensity", {12, 7}}, {"ring", {16, 4}}, {"time", {18, 7}}};
  put32(b, 6);
  for (const auto& [n, ot] : f) {
    put_str(b, n);
    put32(b, ot.first);
    b.push_back(ot.second);
    put32(b, 1);
  }
  b.push_back(0);
  put32(b, step);
  put32(b, step * rings * cols);
  put32(b, step * rings * cols);
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rings; ++r) {
      const double az = c * 0.2 * M_PI / 180, el = (-15 + 2 * r) * M_PI / 180;
      const double d[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
      const double t = room_range(d, 3);
      float v[4] = {float(t * d[0]), float(t * d[1]), float(t * d[2]), float(r * 10)};
      const uint16_t ring = uint16_t(r);
      const float tt = float(c) / cols * 0.1f;
      const size_t o = b.size();
      b.resize(o + step);
      std::memcpy(&b[o], v, 16);
      std::memcpy(&b[o + 16], &ring, 2);
      std::memcpy(&b[o + 18], &tt, 4);
    }
  b.push_back(1);
  return b;
}

// ROS 1 LaserScan: 1081 beams over 270 degrees with intensities, in a 10 x 6 m room (stamp at bytes 4..11).
std::vector<uint8_t> laser_scan() {
  std::vector<uint8_t> b = ros1_header("laser");
  const int n = 1081;
  const float amin = float(-0.75 * M_PI), inc = float(1.5 * M_PI / (n - 1));
  const float f[7] = {amin, -amin, inc, 0.025f / n, 0.025f, 0.02f, 30.0f};
  b.insert(b.end(), (const uint8_t*)f, (const uint8_t*)f + sizeof f);
  put32(b, n);
  for (int i = 0; i < n; ++i) {
    const double a = amin + i * inc, d[2] = {std::cos(a), std::sin(a)};
    const float r = float(room_range(d, 2));
    b.insert(b.end(), (const uint8_t*)&r, (const uint8_t*)&r + 4);
  }
  put32(b, n);
  for (int i = 0; i < n; ++i) {
    const float v = float(1000 + i % 200);
    b.insert(b.end(), (const uint8_t*)&v, (const uint8_t*)&v + 4);
  }
  return b;
}

// The generated recording: a ROS 1 bag or an MCAP file (ROS 1 message encoding, the same message bytes).
struct Recorder {
  bool mcap = false;
  BagWriter bag;
  McapWriter mc;
  bool open(const std::string& path, const std::string& compression) {
    return mcap ? mc.open(path, compression) : bag.open(path, compression);
  }
  void copy_chunks_to(std::FILE* f) { (mcap ? mc.chunk_copy : bag.chunk_copy) = f; }
  // type "pkg/Name" (MCAP: "pkg/msg/Name", as ROS 2 writes it).
  uint32_t add(const std::string& topic, const std::string& type) {
    if (!mcap) return bag.add_connection(topic, type);
    const auto k = type.find('/');
    return mc.add_channel(topic, type.substr(0, k) + "/msg" + type.substr(k), "ros1");
  }
  void write(uint32_t conn, int64_t t, const uint8_t* d, size_t n) {
    if (mcap) mc.write(uint16_t(conn), t, d, n);
    else bag.write(conn, t, d, n);
  }
  bool close() { return mcap ? mc.close() : bag.close(); }
};

// Copies of one message (a std_msgs/Header first: its stamp at bytes 4..11 set to the record time), one
// every period_ns, until `target` bytes are written.
void write_copies(Recorder& w, uint32_t conn, std::vector<uint8_t> msg, int64_t period_ns, uint64_t target,
                  uint64_t& written, uint64_t& messages) {
  for (int64_t i = 0; written < target; ++i) {
    const int64_t t = 1700000000LL * 1000000000LL + i * period_ns;
    const uint32_t sec = uint32_t(t / 1000000000), nsec = uint32_t(t % 1000000000);
    std::memcpy(&msg[4], &sec, 4);
    std::memcpy(&msg[8], &nsec, 4);
    w.write(conn, t, msg.data(), msg.size());
    written += msg.size();
    ++messages;
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc bench import: import speed against cat of the same file (ratio)"};
  fploc::rt::install_cli_messages(app, "fploc bench import");
  int size_mb = 1024, runs = 3;
  std::string kind = "all", compression = "none", keep, format = "bag";
  bool json = false;
  app.add_option("--size-mb", size_mb, "size of each generated bag");
  app.add_option("--kind", kind, "ouster, cloud, laser or all");
  app.add_option("--runs", runs, "timed runs of each command (medians reported)");
  app.add_option("--compression", compression, "chunk compression of the generated file: none, lz4, bz2 (bag), zstd (mcap)");
  app.add_option("--format", format, "generated file: bag (ROS 1 bag 2.0) or mcap (MCAP, ROS 1 message encoding)");
  app.add_option("--keep", keep, "write the bags here and keep them");
  app.add_flag("--json", json, "JSON on stdout");
  std::string baseline;
  app.add_option("--baseline-importer", baseline,
                 "another fploc-import binary (e.g. main's) timed in the same runs (kinds '... [baseline]'); the first "
                 "run's logs of the two are compared byte for byte (same_bytes_as_baseline)");
  bool direct_io = false;
  app.add_flag("--direct-io", direct_io, "this build's importer writes with --direct-io (the baseline importer without it)");
  CLI11_PARSE(app, argc, argv);
  const std::string root = std::getenv("FPLOC_ROOT") ? std::getenv("FPLOC_ROOT") : ".";
  const std::string shared = std::getenv("FPLOC_SHARED_DIR") ? std::string(std::getenv("FPLOC_SHARED_DIR")) : root + "/../shared";
  const fs::path self = fs::canonical("/proc/self/exe").parent_path();
  const std::string importer = (self / "fploc-import").string();
  const fs::path dir = keep.empty() ? fs::temp_directory_path() / ("fploc-bench-import-" + std::to_string(getpid())) : fs::path(keep);
  fs::create_directories(dir);
  const uint64_t target = uint64_t(size_mb) << 20;
  nlohmann::json out = nlohmann::json::array();

  for (const std::string k : {"ouster", "cloud", "laser"}) {
    if (kind != "all" && kind != k) continue;
    if ((format == "mcap") == (compression == "bz2") && compression != "none" && compression != "lz4") {
      std::cerr << "fploc bench import: --compression " << compression << " is not for --format " << format << "\n";
      return 2;
    }
    const std::string bag = (dir / (k + (format == "mcap" ? ".mcap" : ".bag"))).string();
    Recorder w;
    w.mcap = format == "mcap";
    if (!w.open(bag, compression)) {
      std::cerr << "cannot write " << bag << "\n";
      return 1;
    }
    const std::string chunks = (dir / (k + ".chunks." + compression)).string();
    std::FILE* chunk_copy = nullptr;
    if (compression != "none") {
      chunk_copy = std::fopen(chunks.c_str(), "wb");
      w.copy_chunks_to(chunk_copy);
    }
    uint64_t written = 0, messages = 0;
    if (k == "ouster") {
      const std::string src = shared + "/data/ouster/512x10_raw.bag";
      std::string err;
      auto r = open_recording(src, &err);
      if (!r) {
        std::cerr << err << " (needs ../shared/data)\n";
        return 1;
      }
      struct M { uint32_t conn; int64_t t; std::vector<uint8_t> d; std::string type; };
      std::vector<M> ms;
      std::map<uint32_t, uint32_t> conn;
      RawMessage m;
      while (r->next(m)) {
        const auto& c = r->connections().at(m.conn);
        if (!conn.count(m.conn)) conn[m.conn] = w.add(c.topic, c.type);
        ms.push_back({conn[m.conn], m.time_ns, std::vector<uint8_t>(m.data, m.data + m.size), c.type});
      }
      for (int64_t copy = 0; written < target; ++copy) {
        for (auto& x : ms) {
          if (x.type == "std_msgs/String") {
            if (copy == 0) w.write(x.conn, x.t, x.d.data(), x.d.size());
            continue;
          }
          std::vector<uint8_t> d = x.d;
          const size_t n = d.size() - 4;
          if (n > 48) {  // lidar packet (RNG15: frame id at packet byte 2, column headers every 12 + 128 * 4 B after 32)
            uint16_t fid;
            std::memcpy(&fid, &d[4 + 2], 2);
            fid = uint16_t(fid + copy);
            std::memcpy(&d[4 + 2], &fid, 2);
            for (size_t o = 4 + 32; o + 8 <= d.size() - 32; o += 12 + 128 * 4) {
              uint64_t ts;
              std::memcpy(&ts, &d[o], 8);
              ts += uint64_t(copy) * 100000000ull;
              std::memcpy(&d[o], &ts, 8);
            }
          }
          w.write(x.conn, x.t + copy * 100000000LL, d.data(), d.size());
          written += d.size();
          ++messages;
        }
      }
    } else if (k == "laser") {
      write_copies(w, w.add("/scan", "sensor_msgs/LaserScan"), laser_scan(), 25000000LL, target, written, messages);
    } else {
      write_copies(w, w.add("/velodyne_points", "sensor_msgs/PointCloud2"), vlp16_cloud(), 100000000LL, target,
                   written, messages);
    }
    if (!w.close() || (chunk_copy && std::fclose(chunk_copy) != 0)) {
      std::cerr << "writing " << bag << " failed\n";
      return 1;
    }
    const std::string tool = compression == "bz2" ? "bzip2 -dc" : compression == "lz4" ? "lz4 -dc" : compression == "zstd" ? "zstd -dc" : "";
    const uint64_t bytes = fs::file_size(bag);
    const std::string lcm = (dir / (k + ".lcm")).string(), copy = (dir / (k + ".copy")).string();
    run("cat '" + bag + "' > /dev/null");  // warm-up: the page-cache timings below read from memory
    struct Variant {
      std::string name, flag, importer;
    };
    std::vector<Variant> variants = {{k, "", importer}};
    if (k == "ouster") variants.push_back({"ouster --decode", " --decode", importer});
    if (!baseline.empty())  // another importer (e.g. main's) timed in the same runs, its logs compared byte for byte
      for (size_t v = 0, nv = variants.size(); v < nv; ++v)
        variants.push_back({variants[v].name + " [baseline]", variants[v].flag, baseline});
    std::map<std::string, bool> same_bytes;  // variant -> its log equals the baseline's (first run)
    std::vector<double> cat_s, cat_cpu, copy_s, cat_cold_s, tool_s, tool_file_s, tool_cpu;
    std::map<std::string, std::vector<double>> imp_s, imp_cpu, imp_user, imp_sys, imp_cold_s;
    std::vector<double> copy_cpu;
    std::map<std::string, uint64_t> lcm_bytes;
    for (int i = 0; i < runs; ++i) {  // interleaved, so a change in the machine's load hits every command
      cat_s.push_back(run("cat '" + bag + "' > /dev/null"));
      cat_cpu.push_back(last_cpu);
      copy_s.push_back(run("cat '" + bag + "' > '" + copy + "'"));
      copy_cpu.push_back(last_cpu);
      fs::remove(copy);
      if (!tool.empty()) {
        tool_s.push_back(run(tool + " '" + chunks + "' > /dev/null"));
        tool_cpu.push_back(last_cpu);
        tool_file_s.push_back(run(tool + " '" + chunks + "' > '" + copy + "'"));
        fs::remove(copy);
      }
      for (const auto& [name, flag, exe] : variants) {
        const std::string extra = exe == baseline ? "" : (direct_io ? " --direct-io" : "");
        imp_s[name].push_back(run("'" + exe + "' '" + bag + "' --out '" + lcm + "' --quiet" + flag + extra + " > /dev/null"));
        imp_cpu[name].push_back(last_cpu);
        imp_user[name].push_back(last_user);
        imp_sys[name].push_back(last_sys);
        lcm_bytes[name] = fs::file_size(lcm);
        const std::string kept = (dir / (k + flag.substr(flag.empty() ? 0 : 1) + ".first.lcm")).string();
        if (i == 0 && !baseline.empty() && exe != baseline) fs::rename(lcm, kept);  // compared with the baseline's below
        else if (i == 0 && !baseline.empty()) {
          same_bytes[name.substr(0, name.size() - 11)] = std::system(("cmp -s '" + kept + "' '" + lcm + "'").c_str()) == 0;
          fs::remove(kept);
        }
        fs::remove(lcm);
      }
    }
    // Cold: the bag read from the disk (its pages evicted before each run).
    for (int i = 0; i < runs; ++i) {
      evict(bag);
      cat_cold_s.push_back(run("cat '" + bag + "' > /dev/null"));
      for (const auto& [name, flag, exe] : variants) {
        evict(bag);
        const std::string extra = exe == baseline ? "" : (direct_io ? " --direct-io" : "");
        imp_cold_s[name].push_back(run("'" + exe + "' '" + bag + "' --out '" + lcm + "' --quiet" + flag + extra + " > /dev/null"));
        fs::remove(lcm);
      }
    }
    const double t_cat = median(cat_s), t_copy = median(copy_s), t_cat_cold = median(cat_cold_s), cpu_cat = median(cat_cpu);
    for (const auto& [name, flag, exe] : variants) {
      const double t_import = median(imp_s[name]), t_import_cold = median(imp_cold_s[name]), cpu_import = median(imp_cpu[name]);
      nlohmann::json j = {{"kind", name}, {"format", format}, {"compression", compression}, {"bag_bytes", bytes}, {"messages", messages},
                          {"lcm_bytes", lcm_bytes[name]}, {"runs", runs}, {"cat_s", t_cat}, {"cat_copy_s", t_copy},
                          {"import_s", t_import}, {"ratio_vs_cat", t_import / t_cat}, {"ratio_vs_cat_copy", t_import / t_copy},
                          {"import_MBps", bytes / 1e6 / t_import}, {"cold_cat_s", t_cat_cold}, {"cold_import_s", t_import_cold},
                          {"cold_ratio_vs_cat", t_import_cold / t_cat_cold}, {"cat_cpu_s", cpu_cat}, {"import_cpu_s", cpu_import},
                          {"import_user_s", median(imp_user[name])}, {"import_sys_s", median(imp_sys[name])},
                          {"cat_copy_cpu_s", median(copy_cpu)},
                          {"import_runs_s", imp_s[name]}, {"cat_runs_s", cat_s}};
      if (exe != baseline && direct_io) j["direct_io"] = true;
      if (!baseline.empty()) {
        j["importer"] = exe;
        if (same_bytes.count(name)) j["same_bytes_as_baseline"] = same_bytes[name];
      }
      if (!tool.empty()) {
        const double t_tool = median(tool_s), t_tool_file = median(tool_file_s);
        j["decompressor"] = tool;
        j["decompressor_s"] = t_tool;
        j["decompressor_to_file_s"] = t_tool_file;
        j["decompressor_cpu_s"] = median(tool_cpu);
        j["ratio_vs_decompressor"] = t_import / t_tool;
        j["ratio_vs_decompressor_to_file"] = t_import / t_tool_file;
        j["decompressor_runs_s"] = tool_s;
      }
      out.push_back(j);
      if (!json)
        std::printf("%-15s %s: %.0f MB bag (%llu msgs) -> %.0f MB LCM log; medians of %d runs\n"
                    "  page cache: import %.2f s, cat %.2f s (ratio %.2f), cat > copy %.2f s (ratio %.2f)\n"
                    "  cold file:  import %.2f s, cat %.2f s (ratio %.2f)\n  CPU (user+sys): import %.2f s, cat %.2f s\n",
                    name.c_str(), compression.c_str(), bytes / 1e6, (unsigned long long)messages, lcm_bytes[name] / 1e6, runs,
                    t_import, t_cat, t_import / t_cat, t_copy, t_import / t_copy, t_import_cold, t_cat_cold,
                    t_import_cold / t_cat_cold, cpu_import, cpu_cat);
      if (!json && !tool.empty())
        std::printf("  %s of the same chunks: %.2f s to /dev/null (import ratio %.2f), %.2f s to a file (ratio %.2f)\n",
                    tool.c_str(), median(tool_s), t_import / median(tool_s), median(tool_file_s), t_import / median(tool_file_s));
    }
    if (keep.empty()) fs::remove(bag), fs::remove(chunks);
  }
  if (keep.empty()) fs::remove_all(dir);
  if (json) std::cout << fploc::json_text(out, 2) << "\n";  // paths: any bytes
  return 0;
}
