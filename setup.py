"""pip install --no-build-isolation .  (Debian's setuptools; no PyPI)

Builds the Python module with the project's CMake build: in $WETCLOTH_BUILD_DIR
when set, else in build/ when `make` has configured it, else in build/pip
(configured here: the library alone, no tests, viewer or benchmarks)."""
import glob
import os
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.environ.get("WETCLOTH_BUILD_DIR")
        if not build:
            made = os.path.join(HERE, "build")
            build = made if os.path.exists(os.path.join(made, "CMakeCache.txt")) else os.path.join(made, "pip")
        if not os.path.exists(os.path.join(build, "CMakeCache.txt")):
            subprocess.check_call(["cmake", "-S", HERE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                                   "-DWETCLOTH_TESTS=OFF", "-DWETCLOTH_BENCH=OFF", "-DWETCLOTH_VIEWER=OFF",
                                   "-DWETCLOTH_BULLET=OFF", f"-DPython_EXECUTABLE={sys.executable}"])
        subprocess.check_call(["cmake", "--build", build, "--target", "_wetcloth", "-j", str(os.cpu_count() or 1)])
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        built = glob.glob(os.path.join(build, "python", "wetcloth", "_wetcloth" + suffix))
        if not built:
            sys.exit(f"setup.py: {build} has no _wetcloth{suffix} (was it configured for another Python? "
                     "set WETCLOTH_BUILD_DIR to a new folder)")
        dest = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(dest), exist_ok=True)
        shutil.copyfile(built[0], dest)


setup(
    name="wetcloth",
    version="0.1.0",
    description="Wet cloth on contact surfaces: the wetcloth simulator as a NumPy library",
    packages=["wetcloth"],
    package_dir={"": "python"},
    ext_modules=[Extension("wetcloth._wetcloth", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": os.path.join("build", "setuptools")}},
    zip_safe=False,
)
