#pragma once

// One function per binding file; module.cc calls them in layer order.

#include <pybind11/pybind11.h>

namespace imumatch::python {

void BindGeometry(pybind11::module_& m);  // core, camera, imu
void BindMatching(pybind11::module_& m);  // features, prediction, guided and brute-force matching
void BindData(pybind11::module_& m);      // io, synthetic world, evaluation
void BindKlt(pybind11::module_& m);       // KLT tracking, seeded by the IMU and unseeded
void BindTrack(pybind11::module_& m);     // the front end (`imumatch track`)

}  // namespace imumatch::python
