"""Builds the `curvestereo` extension with the project's CMake (python/CMakeLists.txt), for
the interpreter running pip. The metadata is in pyproject.toml; this file adds the package
layout (python/curvestereo) and the CMake step.

Environment: CMAKE_ARGS (extra configure options, e.g. "-DCMAKE_CUDA_ARCHITECTURES=90" or
"-DCMAKE_CUDA_COMPILER=" to leave CUDA out), CMAKE_BUILD_PARALLEL_LEVEL (jobs; default: all
cores). The CMake build lives in build-pip/ (kept between runs, so a rebuild is quick).
"""
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
# setuptools' own scratch (and its egg-info) beside the CMake tree, not in build/ (the
# README's CMake build) nor in the source folders.
BUILD = ROOT / "build-pip"
BUILD.mkdir(exist_ok=True)


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        tree = BUILD / "cmake"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(tree), "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DCURVESTEREO_PYTHON=ON", "-DCURVESTEREO_PYTHON_REQUIRED=ON", "-DCURVESTEREO_BUILD_TESTS=OFF",
        ]
        if shutil.which("ninja") and not (tree / "CMakeCache.txt").exists():
            configure += ["-G", "Ninja"]
        configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.check_call(configure)
        build = ["cmake", "--build", str(tree), "--target", "_curvestereo"]
        if "CMAKE_BUILD_PARALLEL_LEVEL" not in os.environ:
            build += ["-j", str(os.cpu_count() or 1)]
        subprocess.check_call(build)
        built = sorted((tree / "python" / "curvestereo").glob("_curvestereo*" + (".pyd" if os.name == "nt" else ".so")))
        if not built:
            raise RuntimeError(f"CMake built no _curvestereo module in {tree / 'python' / 'curvestereo'}")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[-1], target)


setup(
    package_dir={"": "python"},
    packages=["curvestereo"],
    package_data={"curvestereo": ["*.pyi", "py.typed"]},
    ext_modules=[CMakeExtension("curvestereo._curvestereo")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(BUILD / "setuptools")}, "egg_info": {"egg_base": str(BUILD)}},
)
