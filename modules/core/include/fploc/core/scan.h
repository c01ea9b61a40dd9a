// A full LiDAR revolution as measured: the range image (staggered, row = beam) plus what is needed to
// turn it into points. Transport-free; the LCM message scan_t mirrors it field by field.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace fploc {

struct BeamIntrinsics {
  std::vector<double> altitude_deg;  // one per beam, top beam first
  std::vector<double> azimuth_deg;
  std::vector<int> pixel_shift_by_row;
  double beam_offset_mm = 0.0;       // lidar_origin_to_beam_origin_mm
  // Row-major 4x4, translation in millimetres (Ouster convention).
  std::array<double, 16> lidar_to_sensor{-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1};
  int beams() const { return static_cast<int>(altitude_deg.size()); }
};

enum class ScanStatus : int8_t { kOk = 0, kIncomplete = 1, kBadInput = 2 };

struct Scan {
  int64_t utime = 0;
  int64_t seq = 0;
  int32_t frame_id = 0;
  std::string sensor;
  int height = 0;  // beams
  int width = 0;   // columns
  std::vector<uint32_t> range_mm;      // height*width, row-major [beam][column]; 0 = no return
  std::vector<uint16_t> signal;        // height*width (may be empty)
  std::vector<uint8_t> reflectivity;   // height*width (may be empty)
  std::vector<int64_t> column_utime;   // width
  std::vector<uint16_t> measurement_id;// width
  std::vector<uint8_t> column_valid;   // width (1 = valid)
  BeamIntrinsics beams;
  int32_t missing_columns = 0;
  ScanStatus status = ScanStatus::kOk;

  void resize(int h, int w) {
    height = h;
    width = w;
    range_mm.assign(size_t(h) * w, 0);
    signal.assign(size_t(h) * w, 0);
    reflectivity.assign(size_t(h) * w, 0);
    column_utime.assign(w, 0);
    measurement_id.resize(w);
    for (int c = 0; c < w; ++c) measurement_id[c] = uint16_t(c);
    column_valid.assign(w, 1);
  }
  uint32_t range(int beam, int col) const { return range_mm[size_t(beam) * width + col]; }
};

}  // namespace fploc
