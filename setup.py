"""Package discovery for setuptools (the metadata is in pyproject.toml).

The checkout itself is the package ``rasterhw``; every package under ``hdl/``, ``golden_model/`` and
``sim/`` (a folder per machine in each) is found here, so a new machine's folders need no edit.
``tests/``, ``cocotb_tests/``, ``build/``, ``out/`` and ``.venv/`` are not packages of the
distribution, and this file is not a module of it."""

from setuptools import find_packages, setup
from setuptools.command.build_py import build_py

TREES = ("hdl", "golden_model", "sim")


class BuildPy(build_py):
    """``build_py`` that leaves this file out of the ``rasterhw`` package (the checkout's root)."""

    def find_package_modules(self, package, package_dir):
        found = super().find_package_modules(package, package_dir)
        return [m for m in found if not (package == "rasterhw" and m[1] == "setup")]


setup(packages=["rasterhw"] + [f"rasterhw.{p}" for p in find_packages(include=[f"{t}*" for t in TREES])],
      cmdclass={"build_py": BuildPy})
