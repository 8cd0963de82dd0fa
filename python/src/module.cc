// The `imumatch._imumatch` extension module. The pure-Python package `imumatch` (python/imumatch)
// re-exports it and adds the cv2 conversions.

#include <string>

#include <pybind11/pybind11.h>
#include <opencv2/core.hpp>

#include "bindings.h"
#include "imumatch/core/error.h"

#ifndef IMUMATCH_VERSION
#define IMUMATCH_VERSION "unknown"
#endif

namespace py = pybind11;

PYBIND11_MODULE(_imumatch, m) {
  m.doc() = "imumatch: IMU-guided feature matching between consecutive camera frames (C++ core).";
  m.attr("__version__") = IMUMATCH_VERSION;

  // Exceptions: the library's error types, with the same messages. InputError (bad data in a
  // file) and InvalidArgument (bad value passed in) are ValueErrors; InputError also carries
  // .file and .line (0 when the error is not tied to a line).
  static py::exception<imumatch::Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<imumatch::InvalidArgument> invalid(m, "InvalidArgument", PyExc_ValueError);
  static py::exception<imumatch::InputError> input(m, "InputError", PyExc_ValueError);
  static py::exception<imumatch::OutOfRange> out_of_range(m, "OutOfRange", PyExc_IndexError);
  error.doc() = "Base class of imumatch's errors that are neither bad input nor bad arguments.";
  invalid.doc() = "An argument outside its valid range (a ValueError).";
  input.doc() = "Bad input data; the message names the file and line (.file, .line).";
  out_of_range.doc() = "A query outside the data (e.g. a time outside the IMU log).";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const imumatch::InputError& e) {
      py::object instance = py::reinterpret_borrow<py::object>(input.ptr())(e.what());
      instance.attr("file") = e.file();
      instance.attr("line") = e.line();
      PyErr_SetObject(input.ptr(), instance.ptr());
    } catch (const imumatch::InvalidArgument& e) {
      invalid(e.what());
    } catch (const imumatch::OutOfRange& e) {
      out_of_range(e.what());
    } catch (const imumatch::Error& e) {
      error(e.what());
    } catch (const cv::Exception& e) {
      PyErr_SetString(PyExc_RuntimeError, (std::string("OpenCV: ") + e.what()).c_str());
    }
  });

  imumatch::python::BindGeometry(m);
  imumatch::python::BindMatching(m);
  imumatch::python::BindKlt(m);
  imumatch::python::BindData(m);
  imumatch::python::BindTrack(m);
}
