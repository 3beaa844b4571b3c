"""Build step of `pip install .` (pyproject.toml): bundles the C library.

The package is ctypes over libskinsim.so, so the wheel carries the library
and the data it reads: skinsim/_native/lib/libskinsim.so.0 and
skinsim/_native/share/skinsim/ (the library finds its data at
lib/../share/skinsim next to itself, as in an install prefix). The library is
$SKINSIM_LIB when set, else build/libskinsim.so.0 of this source tree, else
one built here with CMake (build-python/, shared library target only). The
version is the CMake project's. Nothing is fetched from a network.

setuptools' own build folders go to build-python/ (not build/, the CMake
build folder, and not the source tree's package folder).
"""

import os
import re
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))


def _version():
    with open(os.path.join(HERE, "CMakeLists.txt"), encoding="utf-8") as f:
        m = re.search(r"project\(\s*skinsim\s+VERSION\s+([0-9.]+)", f.read())
    if not m:
        raise RuntimeError("setup.py: no 'project(skinsim VERSION x.y.z)' in CMakeLists.txt")
    return m.group(1)


def _library():
    env = os.environ.get("SKINSIM_LIB")
    if env:
        if not os.path.isfile(env):
            raise RuntimeError("setup.py: SKINSIM_LIB=%s is not a file" % env)
        return env
    built = os.path.join(HERE, "build", "libskinsim.so.0")
    if os.path.isfile(built):
        return built
    out = os.path.join(HERE, "build-python")
    subprocess.check_call(["cmake", "-S", HERE, "-B", out, "-DCMAKE_BUILD_TYPE=RelWithDebInfo"])
    subprocess.check_call(["cmake", "--build", out, "--target", "skinsim_shared", "-j2"])
    return os.path.join(out, "libskinsim.so.0")


class BuildWithLibrary(build_py):
    """build_py that also copies the library and the data into the package."""

    def run(self):
        super().run()
        native = os.path.join(self.build_lib, "skinsim", "_native")
        if os.path.isdir(native):
            shutil.rmtree(native)
        os.makedirs(os.path.join(native, "lib"))
        shutil.copy2(_library(), os.path.join(native, "lib", "libskinsim.so.0"))
        shutil.copytree(os.path.join(HERE, "data"), os.path.join(native, "share", "skinsim"))


_WORK = os.path.join(HERE, "build-python")
os.makedirs(_WORK, exist_ok=True)
setup(version=_version(), cmdclass={"build_py": BuildWithLibrary},
      options={"build": {"build_base": os.path.join(_WORK, "setuptools")},
               "egg_info": {"egg_base": _WORK}})
