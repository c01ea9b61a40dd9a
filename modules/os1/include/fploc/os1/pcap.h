// UDP datagrams from a pcap file (libpcap), with IPv4 fragment reassembly, and the rule that sorts
// Ouster datagrams into lidar / IMU (by port, or by size when both share a port).
// libpcap reads the file; Ethernet (+VLAN), Linux SLL/SLL2, raw IPv4 and BSD loopback link types are
// decoded here. Malformed records are counted in PcapStats, never fatal.
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

struct pcap;  // libpcap's handle (pcap_t); pcap.h stays out of this header

namespace fploc::os1 {

struct UdpDatagram {
  int64_t ts_us = 0;        // capture time
  uint32_t src_ip = 0, dst_ip = 0;  // host order
  uint16_t src_port = 0, dst_port = 0;
  const uint8_t* data = nullptr;    // payload; valid until the next call
  size_t size = 0;
};

struct PcapStats {
  uint64_t records = 0;
  uint64_t truncated_records = 0;   // caplen < len, or shorter than the headers claim
  uint64_t non_ipv4 = 0;            // other ethertypes / link types, IPv6
  uint64_t non_udp = 0;
  uint64_t bad_ip_header = 0;
  uint64_t bad_udp_header = 0;
  uint64_t fragments = 0;           // IPv4 fragments seen
  uint64_t reassembled = 0;         // datagrams rebuilt from fragments
  uint64_t fragments_dropped = 0;   // incomplete/expired/over-long fragment sets
  uint64_t datagrams = 0;           // UDP datagrams returned
};

// IPv4 reassembly (RFC 791 offsets in 8-byte units), keyed by (src, dst, id, protocol). At most
// `max_pending` sets are kept; the oldest is dropped (and counted) beyond that.
class Ipv4Reassembler {
 public:
  explicit Ipv4Reassembler(size_t max_pending = 64) : max_pending_(max_pending) {}
  // `ip` is the whole IPv4 packet (header + payload). Returns true and fills `payload` (the IP payload of
  // the complete datagram) when this fragment completed it.
  bool add(const uint8_t* ip, size_t size, int64_t ts_us, std::vector<uint8_t>& payload, PcapStats& st);

 private:
  struct Pending {
    std::vector<uint8_t> data;
    std::vector<uint8_t> have;  // per 8-byte block
    size_t total = 0;           // payload length once the last fragment arrived (0 = unknown)
    int64_t first_ts = 0;
    uint64_t order = 0;
  };
  size_t max_pending_;
  uint64_t counter_ = 0;
  std::map<std::tuple<uint32_t, uint32_t, uint16_t, uint8_t>, Pending> pending_;
};

// Decodes one captured frame of link type `dlt` down to UDP. Returns true with `out` set when it held a
// complete UDP datagram (possibly completed by this fragment; then `out.data` points into `scratch`).
bool decode_frame(int dlt, const uint8_t* frame, size_t caplen, size_t origlen, int64_t ts_us, Ipv4Reassembler& ra,
                  std::vector<uint8_t>& scratch, UdpDatagram& out, PcapStats& st);

class PcapReader {
 public:
  PcapReader();
  ~PcapReader();
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;
  // Opens a file (nanosecond or microsecond pcap; pcapng too, via libpcap). False + error() on failure.
  bool open(const std::string& path);
  // Reads from memory (fuzzing, tests); the buffer must outlive the reader.
  bool open_memory(const uint8_t* data, size_t size);
  // Next UDP datagram; false at the end of the file or on a read error (error() is then non-empty).
  bool next(UdpDatagram& out);
  void close();
  const PcapStats& stats() const { return stats_; }
  const std::string& error() const { return error_; }
  int link_type() const { return dlt_; }

 private:
  bool finish_open(const std::string& name);
  ::pcap* handle_ = nullptr;
  void* mem_file_ = nullptr;  // FILE* for open_memory
  int dlt_ = -1;
  std::string name_;
  std::string error_;
  PcapStats stats_;
  Ipv4Reassembler reassembler_;
  std::vector<uint8_t> scratch_;
};

enum class PacketKind { kLidar, kImu, kOther };

// Sorts Ouster datagrams. Port 0 = any port. A datagram of the lidar size (or of 48 B) whose port fits
// goes to that stream; otherwise a datagram on exactly one of the two ports goes to that stream even
// with a wrong size (so the parser counts it); everything else is kOther.
struct PacketClassifier {
  int lidar_port = 0;
  int imu_port = 0;
  size_t lidar_size = 12608;
  PacketKind classify(uint16_t dst_port, size_t size) const;
};

}  // namespace fploc::os1
