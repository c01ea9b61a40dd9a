// Options (proto/options/recording.proto) -> the cloud-to-scan conversion's options (defaults: the struct's
// own, modules/recording/cloud_to_scan.h; zero in the options = the default where the proto says so).
#pragma once
#include "fploc/recording/cloud_to_scan.h"
#include "options/recording.pb.h"

namespace fploc::config {

rec::CloudOptions config_of(const CloudToScanOptions& o);

}  // namespace fploc::config
