// The test programs' precompiled header (tests/CMakeLists.txt): what most of the suites
// include, parsed once for all of them instead of once a suite. Each suite still includes
// what it uses itself. (A test source that forgot an include is not caught by this
// build; a build with -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON would catch it.)
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <Eigen/Geometry>

#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/stereo.hpp"
#include "test_util.hpp"
