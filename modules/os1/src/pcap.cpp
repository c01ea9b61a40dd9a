#include "fploc/os1/pcap.h"

#include <pcap/pcap.h>

#include <cstdio>
#include <cstring>

#include "fploc/os1/packet.h"

namespace fploc::os1 {
namespace {

inline uint16_t be16(const uint8_t* p) { return uint16_t((p[0] << 8) | p[1]); }
inline uint32_t be32(const uint8_t* p) { return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]; }

constexpr int kDltNull = 0, kDltEn10mb = 1, kDltRaw1 = 12, kDltRaw2 = 14, kDltRaw = 101, kDltLinuxSll = 113,
              kDltLoop = 108, kDltIpv4 = 228, kDltLinuxSll2 = 276;

}  // namespace

bool Ipv4Reassembler::add(const uint8_t* ip, size_t size, int64_t ts_us, std::vector<uint8_t>& payload, PcapStats& st) {
  const size_t ihl = size_t(ip[0] & 0x0F) * 4;
  const uint16_t frag = be16(ip + 6);
  const size_t offset = size_t(frag & 0x1FFF) * 8;
  const bool more = (frag & 0x2000) != 0;
  const size_t len = size - ihl;
  ++st.fragments;
  // Expire sets older than 10 s of capture time.
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (ts_us - it->second.first_ts > 10'000'000) {
      ++st.fragments_dropped;
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
  if (offset + len > 65535 || (more && len % 8 != 0) || len == 0) {
    ++st.fragments_dropped;
    return false;
  }
  auto key = std::make_tuple(be32(ip + 12), be32(ip + 16), be16(ip + 4), ip[9]);
  auto it = pending_.find(key);
  if (it == pending_.end()) {
    if (pending_.size() >= max_pending_) {
      auto oldest = pending_.begin();
      for (auto j = pending_.begin(); j != pending_.end(); ++j)
        if (j->second.order < oldest->second.order) oldest = j;
      ++st.fragments_dropped;
      pending_.erase(oldest);
    }
    it = pending_.emplace(key, Pending{}).first;
    it->second.first_ts = ts_us;
    it->second.order = counter_++;
    it->second.data.resize(65536);
    it->second.have.assign(65536 / 8 + 1, 0);
  }
  Pending& p = it->second;
  if (!more) {
    if (p.total != 0 && p.total != offset + len) {  // two different "last" fragments
      ++st.fragments_dropped;
      pending_.erase(it);
      return false;
    }
    p.total = offset + len;
  }
  std::memcpy(p.data.data() + offset, ip + ihl, len);
  for (size_t b = offset / 8; b < (offset + len + 7) / 8; ++b) p.have[b] = 1;
  if (p.total == 0) return false;
  for (size_t b = 0; b < (p.total + 7) / 8; ++b)
    if (!p.have[b]) return false;
  payload.assign(p.data.begin(), p.data.begin() + long(p.total));
  pending_.erase(it);
  ++st.reassembled;
  return true;
}

bool decode_frame(int dlt, const uint8_t* f, size_t caplen, size_t origlen, int64_t ts_us, Ipv4Reassembler& ra,
                  std::vector<uint8_t>& scratch, UdpDatagram& out, PcapStats& st) {
  if (caplen < origlen) {
    ++st.truncated_records;
    return false;
  }
  size_t off = 0;
  uint16_t ethertype = 0x0800;
  switch (dlt) {
    case kDltEn10mb:
      if (caplen < 14) { ++st.truncated_records; return false; }
      ethertype = be16(f + 12);
      off = 14;
      while (ethertype == 0x8100 || ethertype == 0x88A8) {
        if (caplen < off + 4) { ++st.truncated_records; return false; }
        ethertype = be16(f + off + 2);
        off += 4;
      }
      break;
    case kDltLinuxSll:
      if (caplen < 16) { ++st.truncated_records; return false; }
      ethertype = be16(f + 14);
      off = 16;
      break;
    case kDltLinuxSll2:
      if (caplen < 20) { ++st.truncated_records; return false; }
      ethertype = be16(f);
      off = 20;
      break;
    case kDltNull:
    case kDltLoop: {
      if (caplen < 4) { ++st.truncated_records; return false; }
      uint32_t fam;
      std::memcpy(&fam, f, 4);
      if (fam != 2 && be32(f) != 2) { ++st.non_ipv4; return false; }
      off = 4;
      break;
    }
    case kDltRaw:
    case kDltRaw1:
    case kDltRaw2:
    case kDltIpv4:
      break;
    default:
      ++st.non_ipv4;
      return false;
  }
  if (ethertype != 0x0800) {
    ++st.non_ipv4;
    return false;
  }
  const uint8_t* ip = f + off;
  size_t avail = caplen - off;
  if (avail < 20 || (ip[0] >> 4) != 4) {
    if (avail >= 1 && (ip[0] >> 4) == 6) ++st.non_ipv4;
    else ++st.bad_ip_header;
    return false;
  }
  const size_t ihl = size_t(ip[0] & 0x0F) * 4;
  const size_t total = be16(ip + 2);
  if (ihl < 20 || total < ihl || total > avail) {
    if (total > avail) ++st.truncated_records;
    else ++st.bad_ip_header;
    return false;
  }
  if (ip[9] != 17) {
    ++st.non_udp;
    return false;
  }
  const uint16_t frag = be16(ip + 6);
  const uint8_t* udp;
  size_t udp_avail;
  if ((frag & 0x3FFF) != 0) {  // MF set or offset != 0: a fragment
    if (!ra.add(ip, total, ts_us, scratch, st)) return false;
    udp = scratch.data();
    udp_avail = scratch.size();
  } else {
    udp = ip + ihl;
    udp_avail = total - ihl;
  }
  if (udp_avail < 8) {
    ++st.bad_udp_header;
    return false;
  }
  const size_t ulen = be16(udp + 4);
  if (ulen < 8 || ulen > udp_avail) {
    ++st.bad_udp_header;
    return false;
  }
  out.ts_us = ts_us;
  out.src_ip = be32(ip + 12);
  out.dst_ip = be32(ip + 16);
  out.src_port = be16(udp);
  out.dst_port = be16(udp + 2);
  out.data = udp + 8;
  out.size = ulen - 8;
  ++st.datagrams;
  return true;
}

PcapReader::PcapReader() = default;
PcapReader::~PcapReader() { close(); }

void PcapReader::close() {
  if (handle_) pcap_close(handle_);  // also closes the FILE* of open_memory
  handle_ = nullptr;
  mem_file_ = nullptr;
}

bool PcapReader::finish_open(const std::string& name) {
  name_ = name;
  stats_ = PcapStats{};
  reassembler_ = Ipv4Reassembler{};
  dlt_ = pcap_datalink(handle_);
  return true;
}

bool PcapReader::open(const std::string& path) {
  close();
  char err[PCAP_ERRBUF_SIZE] = {0};
  handle_ = pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_MICRO, err);
  if (!handle_) {
    error_ = path + ": " + err;
    return false;
  }
  error_.clear();
  return finish_open(path);
}

bool PcapReader::open_memory(const uint8_t* data, size_t size) {
  close();
  if (size == 0) {
    error_ = "<memory>: empty";
    return false;
  }
  FILE* fp = fmemopen(const_cast<uint8_t*>(data), size, "rb");
  if (!fp) {
    error_ = "<memory>: fmemopen failed";
    return false;
  }
  char err[PCAP_ERRBUF_SIZE] = {0};
  handle_ = pcap_fopen_offline_with_tstamp_precision(fp, PCAP_TSTAMP_PRECISION_MICRO, err);
  if (!handle_) {
    fclose(fp);
    error_ = std::string("<memory>: ") + err;
    return false;
  }
  mem_file_ = fp;
  error_.clear();
  return finish_open("<memory>");
}

bool PcapReader::next(UdpDatagram& out) {
  if (!handle_) return false;
  for (;;) {
    pcap_pkthdr* h = nullptr;
    const u_char* d = nullptr;
    const int rc = pcap_next_ex(handle_, &h, &d);
    if (rc == PCAP_ERROR_BREAK) return false;  // end of file
    if (rc < 0) {
      error_ = name_ + ": record " + std::to_string(stats_.records + 1) + ": " + pcap_geterr(handle_);
      return false;
    }
    if (rc == 0) continue;
    ++stats_.records;
    const int64_t ts = int64_t(h->ts.tv_sec) * 1000000 + h->ts.tv_usec;
    if (decode_frame(dlt_, d, h->caplen, h->len, ts, reassembler_, scratch_, out, stats_)) return true;
  }
}

PacketKind PacketClassifier::classify(uint16_t port, size_t size) const {
  const bool lp = lidar_port == 0 || port == lidar_port;
  const bool ip = imu_port == 0 || port == imu_port;
  if (size == lidar_size && lp) return PacketKind::kLidar;
  if (size == kImuPacketSize && ip) return PacketKind::kImu;
  if (lidar_port != 0 && port == lidar_port && (imu_port != lidar_port)) return PacketKind::kLidar;
  if (imu_port != 0 && port == imu_port && (imu_port != lidar_port)) return PacketKind::kImu;
  return PacketKind::kOther;
}

}  // namespace fploc::os1
