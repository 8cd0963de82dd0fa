#pragma once

#include <string>

#include "imumatch/io/synthetic_io.h"
#include "imumatch/sim/synthetic_sequence.h"

namespace imumatch {

// Writes a synthetic sequence in the EuRoC / ASL layout that EuRoC readers (imumatch's own,
// Kalibr, OpenVINS, VINS-Fusion, Basalt, ORB-SLAM3) take:
//   mav0/cam0/data.csv, data/<t_ns>.png   8-bit gray (BGR to gray by cv::cvtColor's weights)
//   mav0/cam0/sensor.yaml                 T_BS = body_from_cam (body = IMU), rate_hz, resolution,
//                                         pinhole intrinsics, the lens model and its coefficients
//   mav0/imu0/data.csv, sensor.yaml       the simulated samples; T_BS identity, the noise figures
//   mav0/depth0/data.csv, data/*.png      the exact depth (uint16, depth_scale per metre) on cam0's
//   mav0/depth0/sensor.yaml               grid and timestamps (imumatch's extension of the layout)
//   mav0/state_groundtruth_estimate0/data.csv
//                                         at the frame times: world_from_imu, the IMU's velocity,
//                                         and in the bias columns the simulator's initial bias (its
//                                         random walk during the sequence is not recorded)
//   mav0/body.yaml
// Timestamps are the frames' t_ns exactly. The same folder rules as WriteSyntheticSequence
// (created when missing, refused when not empty unless overwrite). Throws Error when writing
// fails, InvalidArgument for a sequence without frames or with decreasing timestamps.
void WriteSyntheticSequenceAsEuroc(const SyntheticSequence& sequence, const std::string& dir,
                                   const SyntheticWriteOptions& write_options = {});

}  // namespace imumatch
