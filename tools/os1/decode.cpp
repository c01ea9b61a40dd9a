// fploc os1 decode: decodes an Ouster pcap with its metadata; JSON summary on stdout (--json), PCD files
// per frame (--out-pcd), and a check against an ouster-sdk digest file (--digest).
//
// The SDK digest (ouster-sdk python/src/ouster/client/_digest.py, FieldDigest.from_scan) is
// md5(numpy_array.tobytes()) of each LidarScan field: the STAGGERED image (the SDK stores scans as
// measured), row-major [beam][column], little-endian, RANGE as uint32 (20-bit masked). Invalid columns
// (status bit 0 clear) stay zero. TIMESTAMP/STATUS/ENCODER_COUNT are per column as uint64,
// MEASUREMENT_ID as uint16, FRAME_ID as a decimal string. packet_hash is one md5 over every lidar packet's
// fields in order (RANGE: H x 16 uint32 per packet, SIGNAL/NEAR_IR uint16, REFLECTIVITY and FLAGS uint8,
// headers: 16 values per packet in their wire type). Scan SIGNAL/NEAR_IR are uint16, REFLECTIVITY uint8
// (the low 8 bits of the legacy 16-bit field).
#include <openssl/evp.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fploc/core/text_out.h"
#include "fploc/core/xyz.h"
#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"
#ifdef FPLOC_HAVE_PCL
#include "pcd_writer.h"
#include "fploc/runtime/cli_messages.h"
#endif

using namespace fploc;
using namespace fploc::os1;
using json = nlohmann::json;

namespace {

class Md5 {
 public:
  Md5() : ctx_(EVP_MD_CTX_new()) { EVP_DigestInit_ex(ctx_, EVP_md5(), nullptr); }
  ~Md5() { EVP_MD_CTX_free(ctx_); }
  Md5(const Md5&) = delete;
  Md5& operator=(const Md5&) = delete;
  void update(const void* p, size_t n) { EVP_DigestUpdate(ctx_, p, n); }
  template <class T>
  void update(const std::vector<T>& v) { update(v.data(), v.size() * sizeof(T)); }
  std::string hex() {
    unsigned char d[EVP_MAX_MD_SIZE];
    unsigned n = 0;
    EVP_DigestFinal_ex(ctx_, d, &n);
    static const char* k = "0123456789abcdef";
    std::string s;
    for (unsigned i = 0; i < n; ++i) s += k[d[i] >> 4], s += k[d[i] & 15];
    return s;
  }

 private:
  EVP_MD_CTX* ctx_;
};

template <class T>
std::string md5_of(const std::vector<T>& v) {
  Md5 m;
  m.update(v);
  return m.hex();
}

// A LidarScan as the ouster SDK builds it, for the conformance digests (all fields, wire types).
struct SdkScan {
  int H = 0, W = 0;
  int frame_id = -1;
  std::vector<uint32_t> range;
  std::vector<uint16_t> signal, nir;
  std::vector<uint8_t> refl;
  std::vector<uint64_t> ts, status, encoder;
  std::vector<uint16_t> mid;
  void start(int h, int w, int fid) {
    H = h, W = w, frame_id = fid;
    range.assign(size_t(h) * w, 0), signal.assign(range.size(), 0), nir = signal, refl.assign(range.size(), 0);
    ts.assign(w, 0), status = encoder = ts;
    mid.assign(w, 0);
  }
  json digest() const {
    return {{"FRAME_ID", std::to_string(frame_id)}, {"TIMESTAMP", md5_of(ts)},     {"STATUS", md5_of(status)},
            {"MEASUREMENT_ID", md5_of(mid)},          {"ENCODER_COUNT", md5_of(encoder)}, {"RANGE", md5_of(range)},
            {"SIGNAL", md5_of(signal)},               {"NEAR_IR", md5_of(nir)},      {"REFLECTIVITY", md5_of(refl)}};
  }
};

struct SdkDigester {
  explicit SdkDigester(const PacketFormat& fmt) : f(fmt) {}
  PacketFormat f;
  SdkScan cur;
  std::vector<json> scans;
  Md5 p_flags, p_range, p_signal, p_refl, p_nir, p_ts, p_mid, p_fid, p_enc, p_status;

  void add(const uint8_t* data, size_t size) {
    LidarPacketView v;
    if (!v.reset(f, data, size)) return;
    const int C = f.columns_per_packet, H = f.pixels_per_column;
    // Packet fields: H x C arrays, row-major.
    std::vector<uint32_t> r(size_t(H) * C);
    std::vector<uint16_t> s16(r.size()), n16(r.size());
    std::vector<uint8_t> f16(r.size()), flags(r.size());
    for (int b = 0; b < H; ++b)
      for (int c = 0; c < C; ++c) {
        const size_t i = size_t(b) * C + c;
        r[i] = v.range_mm(c, b), s16[i] = v.signal(c, b), f16[i] = uint8_t(v.reflectivity(c, b)), n16[i] = v.near_ir(c, b);
        flags[i] = uint8_t(v.pixel(c, b)[3] >> 4);  // legacy FLAGS: bits 28..31 of word 0
      }
    p_range.update(r), p_flags.update(flags), p_signal.update(s16), p_refl.update(f16), p_nir.update(n16);
    std::vector<uint64_t> ts(C);
    std::vector<uint16_t> mid(C), fid(C);
    std::vector<uint32_t> enc(C), st(C);
    for (int c = 0; c < C; ++c) {
      auto h = v.column(c);
      ts[c] = h.timestamp_ns, mid[c] = h.measurement_id, fid[c] = h.frame_id, enc[c] = h.encoder_count, st[c] = h.status;
    }
    p_ts.update(ts), p_mid.update(mid), p_fid.update(fid), p_enc.update(enc), p_status.update(st);
    // Scan batching (frame change ends the scan; invalid columns are skipped).
    const int fid0 = v.packet_frame_id();
    if (cur.frame_id != fid0) {
      if (cur.frame_id >= 0) scans.push_back(cur.digest());
      cur.start(H, f.columns_per_frame, fid0);
    }
    for (int c = 0; c < C; ++c) {
      auto h = v.column(c);
      if (!h.valid() || h.measurement_id >= cur.W) continue;
      const int m = h.measurement_id;
      cur.ts[m] = h.timestamp_ns, cur.mid[m] = h.measurement_id, cur.status[m] = h.status, cur.encoder[m] = h.encoder_count;
      for (int b = 0; b < H; ++b) {
        const size_t i = size_t(b) * cur.W + m;
        cur.range[i] = v.range_mm(c, b), cur.signal[i] = v.signal(c, b), cur.refl[i] = uint8_t(v.reflectivity(c, b)), cur.nir[i] = v.near_ir(c, b);
      }
    }
  }
  json finish() {
    if (cur.frame_id >= 0) scans.push_back(cur.digest());
    json pk = {{"FLAGS", p_flags.hex()}, {"RANGE", p_range.hex()}, {"SIGNAL", p_signal.hex()}, {"REFLECTIVITY", p_refl.hex()}, {"NEAR_IR", p_nir.hex()},
               {"TIMESTAMP", p_ts.hex()}, {"MEASUREMENT_ID", p_mid.hex()}, {"FRAME_ID", p_fid.hex()},
               {"ENCODER_COUNT", p_enc.hex()}, {"STATUS", p_status.hex()}};
    return {{"packet_hash", pk}, {"scans", scans}};
  }
};

// Compares our digests with the SDK's file: per key "match" / "differ" / "absent".
json compare_digest(const json& ours, const json& ref) {
  json out = json::object();
  auto cmp = [](const json& a, const json& b) {
    json r = json::object();
    for (auto& [k, v] : b.items()) r[k] = !a.contains(k) ? "absent" : (a[k] == v ? "match" : "differ");
    return r;
  };
  if (ref.contains("packet_hash")) out["packet_hash"] = cmp(ours["packet_hash"], ref["packet_hash"]);
  json scans = json::array();
  if (ref.contains("scans"))
    for (size_t i = 0; i < ref["scans"].size(); ++i)
      scans.push_back(i < ours["scans"].size() ? cmp(ours["scans"][i], ref["scans"][i]) : json("missing scan"));
  out["scans"] = scans;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc os1 decode: decode an Ouster pcap (legacy / RNG19 / RNG15 low-data-rate profiles) with its metadata JSON"};
  fploc::rt::install_cli_messages(app, "fploc os1 decode");
  std::string pcap_path, meta_path, pcd_dir, digest_path;
  bool as_json = false;
  int lidar_port = 0, imu_port = 0;
  app.add_option("--pcap", pcap_path, "capture file (pcap/pcapng)")->required();
  app.add_option("--metadata", meta_path, "sensor metadata JSON (flat, nested or reduced)")->required();
  app.add_flag("--json", as_json, "JSON summary on stdout");
  app.add_option("--out-pcd", pcd_dir, "write each frame as DIR/frame_<n>_<frame_id>.pcd (organized, destaggered)");
  app.add_option("--digest", digest_path, "compare with an ouster-sdk digest JSON (FieldDigest per scan)");
  app.add_option("--lidar-port", lidar_port, "lidar UDP port (0 = any; sorted by size)");
  app.add_option("--imu-port", imu_port, "IMU UDP port (0 = any; sorted by size)");
  CLI11_PARSE(app, argc, argv);

  SensorInfo info;
  try {
    info = load_metadata(meta_path);
  } catch (const MetadataError& e) {
    std::cerr << "fploc os1 decode: " << e.what() << "\n";
    return 2;
  }
  PcapReader reader;
  if (!reader.open(pcap_path)) {
    std::cerr << "fploc os1 decode: " << reader.error() << "\n";
    return 2;
  }
#ifndef FPLOC_HAVE_PCL
  if (!pcd_dir.empty()) {
    std::cerr << "fploc os1 decode: built without PCL, --out-pcd unavailable\n";
    return 2;
  }
#endif
  if (!pcd_dir.empty()) std::filesystem::create_directories(pcd_dir);

  FrameAssembler fa(info);
  SdkDigester sdk(fa.format());
  PacketClassifier cls{lidar_port, imu_port, fa.format().lidar_packet_size()};
  const XyzLut lut = make_xyz_lut(info.beams, info.columns_per_frame);
  uint64_t lidar_packets = 0, imu_packets = 0, imu_bad = 0, other = 0, valid_returns = 0;
  json range_md5 = json::array(), frame_ids = json::array(), missing = json::array();
  std::vector<std::string> errors;
  std::map<std::string, uint64_t> packet_errors;
  int frame_index = 0;

  auto handle = [&](std::vector<Scan>& frames) {
    for (Scan& s : frames) {
      range_md5.push_back(md5_of(s.range_mm));
      frame_ids.push_back(s.frame_id);
      missing.push_back(s.missing_columns);
      for (uint32_t r : s.range_mm) valid_returns += r != 0;
#ifdef FPLOC_HAVE_PCL
      if (!pcd_dir.empty()) {
        const std::string p = pcd_dir + "/frame_" + std::to_string(frame_index) + "_" + std::to_string(s.frame_id) + ".pcd";
        const std::string err = write_pcd(s, lut, p);
        if (!err.empty()) errors.push_back(err);
      }
#endif
      std::cerr << "frame " << s.frame_id << ": " << s.height << "x" << s.width << ", missing columns "
                << s.missing_columns << "\n";
      ++frame_index;
    }
    frames.clear();
  };

  std::vector<Scan> frames;
  UdpDatagram d;
  while (reader.next(d)) {
    switch (cls.classify(d.dst_port, d.size)) {
      case PacketKind::kLidar: {
        ++lidar_packets;
        const PacketError e = fa.add_packet(d.data, d.size, frames);
        if (e != PacketError::kNone) ++packet_errors[to_string(e)];
        sdk.add(d.data, d.size);
        handle(frames);
        break;
      }
      case PacketKind::kImu: {
        ImuSample s;
        if (parse_imu_packet(d.data, d.size, s)) ++imu_packets;
        else ++imu_bad;
        break;
      }
      case PacketKind::kOther:
        ++other;
        break;
    }
  }
  fa.flush(frames);
  handle(frames);
  if (!reader.error().empty()) errors.push_back(reader.error());

  const auto& st = fa.stats();
  const auto& ps = reader.stats();
  json out = {{"packets", lidar_packets},
              {"frames", st.frames},
              {"complete_frames", st.complete_frames},
              {"columns_per_frame", info.columns_per_frame},
              {"pixels_per_column", info.pixels_per_column},
              {"valid_returns", valid_returns},
              {"imu_packets", imu_packets},
              {"range_md5", range_md5},
              {"frame_ids", frame_ids},
              {"missing_columns", missing},
              {"sensor", info.sensor_name()},
              {"udp_profile", to_string(info.profile)},
              {"lidar_packet_bytes", fa.format().lidar_packet_size()},
              {"bad_input",
               {{"lidar_wrong_size", st.wrong_size}, {"bad_columns", st.bad_measurement_id},
                {"stale_packets", st.stale_packets}, {"duplicate_columns", st.duplicate_columns},
                {"invalid_columns", st.invalid_columns}, {"imu_bad", imu_bad}, {"other_datagrams", other}}},
              {"pcap",
               {{"records", ps.records}, {"udp_datagrams", ps.datagrams}, {"ip_fragments", ps.fragments},
                {"reassembled", ps.reassembled}, {"fragments_dropped", ps.fragments_dropped},
                {"truncated_records", ps.truncated_records}, {"non_ipv4", ps.non_ipv4}, {"non_udp", ps.non_udp},
                {"bad_ip_header", ps.bad_ip_header}, {"bad_udp_header", ps.bad_udp_header}}},
              {"errors", errors}};
  if (!digest_path.empty()) {
    std::ifstream f(digest_path);
    json ref;
    try {
      f >> ref;
      json ours = sdk.finish();
      out["sdk_digest"] = ours;
      out["digest_check"] = compare_digest(ours, ref);
    } catch (const std::exception& e) {
      errors.push_back(digest_path + ": " + e.what());
      out["errors"] = errors;
    }
  }
  for (const auto& e : errors) std::cerr << "fploc os1 decode: " << e << "\n";
  std::cerr << lidar_packets << " lidar packets, " << st.frames << " frames (" << st.complete_frames << " complete), "
            << imu_packets << " IMU packets\n";
  if (as_json) std::cout << fploc::json_text(out, 2) << "\n";
  return errors.empty() ? 0 : 1;  // a capture cut short, a PCD or digest that failed: the summary above, then exit 1
}
