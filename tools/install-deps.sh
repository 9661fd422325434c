#!/usr/bin/env bash
# Installs curvestereo's build and test dependencies from Debian / Ubuntu packages: the
# compiler and CMake, the libraries (Eigen, yaml-cpp, OpenEXR, libpng, doctest), the Vulkan
# backend's headers, shader compiler, Mesa's lavapipe (a CPU Vulkan device, so the Vulkan
# backend is tested without a GPU) and validation layers, and the Python module's
# pybind11, NumPy and pytest, and what installing the module with pip needs (pip, venv,
# setuptools, wheel; docs/guide.md "Python"), and the log readers' compression, SQLite and JPEG
# libraries (zstd, lz4, bz2, sqlite3, zlib, libjpeg-turbo), and Dask's distributed (python3 -m
# curvestereo.batch). The one list of packages: the README's set-up
# and CI use it.
# CUDA is not installed here: the CUDA backend builds when nvcc is on the PATH.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends \
  cmake g++ make libeigen3-dev libyaml-cpp-dev libopenexr-dev libpng-dev doctest-dev \
  libvulkan-dev glslang-tools mesa-vulkan-drivers vulkan-validationlayers \
  python3-dev pybind11-dev python3-numpy python3-pytest \
  python3-pip python3-venv python3-setuptools python3-wheel python3-distributed \
  libzstd-dev liblz4-dev libbz2-dev libsqlite3-dev zlib1g-dev libjpeg-dev
