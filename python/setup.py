"""Install-time step of the curvflow package: copies the shared library
built by CMake (target curvflow_shared) into the package, so that an
installed curvflow does not depend on the checkout. The library is taken
from $CURVFLOW_LIB_DIR, else $BUILD_DIR, else <checkout>/build; the
install fails with a clear message when none holds it. Metadata is in
pyproject.toml."""
import os
import pathlib
import shutil

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

HERE = pathlib.Path(__file__).resolve().parent
SONAME = "libcurvflow.so.0"


def find_library():
    dirs = [os.environ.get("CURVFLOW_LIB_DIR"), os.environ.get("BUILD_DIR"), str(HERE.parent / "build")]
    for d in filter(None, dirs):
        p = pathlib.Path(d) / SONAME
        if p.is_file():
            return p.resolve()  # the versioned file, not the symlink
        if os.environ.get("CURVFLOW_LIB_DIR") == d:
            break  # an explicit choice is not replaced by another copy
    raise SystemExit("curvflow: %s not found in %s; build the library first "
                     "(cmake -S . -B build && cmake --build build --target curvflow_shared) or set "
                     "CURVFLOW_LIB_DIR" % (SONAME, ", ".join(filter(None, dirs))))


class BuildWithLibrary(build_py):
    def run(self):
        super().run()
        target = pathlib.Path(self.build_lib) / "curvflow" / SONAME
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(find_library(), target)


class BinaryDistribution(Distribution):
    # the wheel carries a platform-specific shared library
    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": BuildWithLibrary}, distclass=BinaryDistribution)
