#include "pcd_writer.h"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

std::string write_pcd(const fploc::Scan& scan, const fploc::XyzLut& lut, const std::string& path) {
  pcl::PointCloud<pcl::PointXYZI> cloud(uint32_t(scan.width), uint32_t(scan.height));
  cloud.is_dense = false;
  for (int u = 0; u < scan.height; ++u) {
    for (int c = 0; c < scan.width; ++c) {
      const int mid = scan.measurement_id.empty() ? c : scan.measurement_id[c];
      const Eigen::Vector3f p = lut_point(lut, u, mid, scan.range(u, c));
      auto& q = cloud.at(fploc::destagger_column(scan.beams, u, c, scan.width), u);
      q.x = p.x(), q.y = p.y(), q.z = p.z();
      q.intensity = scan.signal.empty() ? 0.f : float(scan.signal[size_t(u) * scan.width + c]);
    }
  }
  try {
    if (pcl::io::savePCDFileBinary(path, cloud) != 0) return path + ": PCL could not write the file";
  } catch (const std::exception& e) {
    return path + ": " + e.what();
  }
  return "";
}
