"""Installs the gyrochar package from the checkout with Debian's pip and setuptools, offline:

    python3 -m pip install --no-build-isolation host_tools/python        (add --user, or in a venv)

The native module is built by the project's own CMake (the host tools' libraries and
host_tools/python/module.cpp; Debian's pybind11-dev, python3-dev and the packages
toolchain/build.sh installs), for the interpreter that runs pip: a fresh configure in pip's build
folder, or, with GYROCHAR_CMAKE_BUILD_DIR set to a configured build folder (build/host), the
target gyrochar_python_native built there and taken from it (that folder's interpreter must be of
the same Python version). docs/python.md, "Build, import, install".
"""

import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]  # the repository: host_tools/python/../..


def version():
    match = re.search(r"project\(gyrochar VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not match:
        raise RuntimeError("no 'project(gyrochar VERSION ...)' in %s" % (ROOT / "CMakeLists.txt"))
    return match.group(1)


class CMakeBuild(build_ext):
    """Builds gyrochar._native with the project's CMake instead of compiling sources itself."""

    def build_extension(self, ext):
        build = os.environ.get("GYROCHAR_CMAKE_BUILD_DIR")
        if build:
            build = pathlib.Path(build).resolve()
            if not (build / "CMakeCache.txt").is_file():
                raise RuntimeError("GYROCHAR_CMAKE_BUILD_DIR=%s is not a configured CMake build folder" % build)
        else:
            build = pathlib.Path(self.build_temp).resolve() / "cmake"
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []  # Ninja builds on every core
            subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build), *generator, "-DCMAKE_BUILD_TYPE=Release",
                                   "-DGYROCHAR_TESTS=OFF", "-DPython3_EXECUTABLE=" + sys.executable])
        jobs = ["-j", str(self.parallel)] if self.parallel else []
        subprocess.check_call(["cmake", "--build", str(build), "--target", "gyrochar_python_native", *jobs])
        built = sorted((build / "python" / "gyrochar").glob("_native*.so"))
        if len(built) != 1:
            raise RuntimeError("expected one _native module in %s, found %s" % (build / "python" / "gyrochar",
                                                                                 [p.name for p in built] or "none"))
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


setup(
    name="gyrochar",
    version=version(),
    description="Allan-variance family of gyro and clock records: gyrochar-analyze's engine on numpy arrays",
    python_requires=">=3.9",
    install_requires=["numpy"],
    packages=["gyrochar"],
    ext_modules=[Extension("gyrochar._native", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
)
