"""Shared fixtures of the Python binding tests (run by ctest with PYTHONPATH set to the build)."""

import json
import os
import subprocess

import pytest


def data_dir():
    d = os.environ.get("IMUMATCH_DATA_DIR", "")
    if not d or not os.path.isdir(d):
        pytest.fail("IMUMATCH_DATA_DIR does not name the shared data folder: %r" % d)
    return d


def cpp_reference(*args):
    """JSON printed by the C++ reference program (python_reference.cc) for the same pipeline."""
    exe = os.environ.get("IMUMATCH_PYTHON_REFERENCE", "")
    if not exe or not os.path.exists(exe):
        pytest.fail("IMUMATCH_PYTHON_REFERENCE does not name the reference program: %r" % exe)
    out = subprocess.run([exe, *args], check=True, capture_output=True, text=True, timeout=240)
    return json.loads(out.stdout)
