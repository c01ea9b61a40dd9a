// Cloud-to-scan: a recorded spinning-LiDAR point cloud (point_cloud2_t: the PointCloud2 bytes and field
// layout `fploc import` keeps) -> scan_t, the range image the segmenter takes. The conversion is
// modules/recording's cloud_to_scan, the one `fploc import --decode` runs, so both give the same scan_t
// byte for byte (rings from the ring/channel/line field or from the elevations, columns from the
// azimuths; Ouster, Velodyne, Hesai, Robosense and Livox layouts). graphs/replay-clouds.pbtxt puts it
// in front of the replay pipeline, the way the OS-1 driver decodes recorded Ouster packets.
#include <fploc/point_cloud2_t.hpp>
#include <fploc/scan_t.hpp>

#include "fploc/adapters/point_cloud2_t.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/config/recording.h"
#include "fploc/recording/cloud_to_scan.h"
#include "fploc/runtime/node.h"
#include "options/recording.pb.h"

namespace {

class CloudToScanNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"cloud_to_scan", "cloud_to_scan", "recorded point clouds (point_cloud2_t) -> range images (scan_t)",
            {fploc::rt::input<fploc::point_cloud2_t>("clouds", "POINT_CLOUD"),
             fploc::rt::output<fploc::scan_t>("scan", "OS1_SCAN")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    opt_ = fploc::config::config_of(ctx.options<fploc::CloudToScanOptions>());
    out_ = ctx.advertise<fploc::scan_t>("scan");
    ctx.subscribe<fploc::point_cloud2_t>("clouds", [this](const fploc::point_cloud2_t& m) { on_cloud(m); });
  }

 private:
  void on_cloud(const fploc::point_cloud2_t& m) {
    std::string err;
    fploc::rec::CloudStats stats;
    if (!fploc::adapters::from_msg(m, cloud_, &err) || !fploc::rec::cloud_to_scan(cloud_, opt_, scan_, &stats, &err)) {
      ctx_->error("cloud seq " + std::to_string(m.seq) + " from " + m.source + ": " + err);
      return;
    }
    // An organised cloud with stray points (binned by azimuth, the rest keeps its columns): said when it starts or
    // its count of rings binned whole changes, not for every cloud.
    const int strays = stats.stray_points || stats.relabelled_points ? 1 + stats.azimuth_rings : 0;
    if (strays != last_strays_) {
      last_strays_ = strays;
      if (strays)
        ctx_->status_changed("cloud seq " + std::to_string(m.seq) + " from " + m.source + ": organised, " +
                             std::to_string(stats.stray_points) + " stray points binned by azimuth (off their ring's row "
                             "or more than a column off its shift; " + std::to_string(stats.azimuth_rings) +
                             " rings whole), " + std::to_string(stats.relabelled_points) +
                             " points with a ring value no row has taken as their row's ring");
      else
        ctx_->status_changed("cloud seq " + std::to_string(m.seq) + " from " + m.source + ": no stray points", false);
    }
    // As `fploc import --decode` names and numbers them.
    scan_.seq = m.seq;
    scan_.frame_id = int32_t(m.seq & 0xFFFF);
    scan_.sensor = "PointCloud2 " + m.source + " (" + std::to_string(scan_.height) + " rings)";
    fploc::adapters::to_msg(scan_, msg_);
    out_.publish(msg_);
  }

  fploc::rt::Context* ctx_ = nullptr;
  int last_strays_ = 0;  // 0: the last cloud had no stray points; else 1 + its rings binned by azimuth whole
  fploc::rec::CloudOptions opt_;
  fploc::rec::PointCloud2 cloud_;
  fploc::Scan scan_;  // buffers reused from cloud to cloud
  fploc::scan_t msg_;
  fploc::rt::Publisher<fploc::scan_t> out_;
};

}  // namespace
FPLOC_REGISTER_NODE(CloudToScanNode)
