"""Package discovery, the version and the build folder for setuptools (the rest of the metadata is
in pyproject.toml).

* Packages: the checkout itself is the package ``rasterhw``; every folder under ``hdl/``,
  ``golden_model/``, ``sim/`` and ``cocotb_tests/`` (a folder per machine in each) is declared here,
  data-only ones (``sim/report/templates``) as namespace packages, so a new machine's folders need no
  edit and every shipped file belongs to a declared package (setuptools' "Package ... is absent from
  the ``packages`` configuration" warning, which a future setuptools turns into missing files).
  ``tests/``, ``build/``, ``out/`` and ``.venv/`` are not packages of the distribution, and this file
  is not a module of it.
* Version: ``sim/version.py``: the release (``__init__.py``) with the commit as a local label in a git
  checkout (``0.1.0+g0d10752e62``), the release alone from a tarball without ``.git``; written into
  the wheel as ``rasterhw/_version.py`` so that the installed package knows its commit.
* Build folder: a fresh temporary one per build, never ``build/`` of the checkout (that is the
  simulation cache, ``sim/paths.py``): a module moved or removed since an earlier build cannot be
  shipped from a stale ``build/lib``; ``build_py`` also empties the package's folder in whatever
  build folder it is given before it copies.
"""

import atexit
import importlib.util
import re
import shutil
import tempfile
from pathlib import Path

from setuptools import find_namespace_packages, setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
TREES = ("hdl", "golden_model", "sim", "cocotb_tests")


def _version() -> str:
    release = re.search(r'^__version__ = "([^"]+)"', (HERE / "__init__.py").read_text(), re.M).group(1)
    spec = importlib.util.spec_from_file_location("_rasterhw_version", HERE / "sim" / "version.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)   # stdlib only at import: the package itself is not importable here
    return mod.git_version(HERE, release) or release


VERSION = _version()


class BuildPy(build_py):
    """``build_py`` that starts from an empty package folder, leaves this file out of the
    ``rasterhw`` package (the checkout's root) and writes ``_version.py``."""

    def run(self):
        if not self.editable_mode:
            shutil.rmtree(Path(self.build_lib) / "rasterhw", ignore_errors=True)
        super().run()
        if not self.editable_mode:
            out = Path(self.build_lib) / "rasterhw" / "_version.py"
            out.write_text(f'"""Written by setup.py when this wheel was built."""\n\nVERSION = "{VERSION}"\n')

    def find_package_modules(self, package, package_dir):
        found = super().find_package_modules(package, package_dir)
        return [m for m in found if not (package == "rasterhw" and m[1] == "setup")]


def _packages() -> list[str]:
    found = find_namespace_packages(include=[f"{t}*" for t in TREES], exclude=["*__pycache__*"])
    return ["rasterhw"] + [f"rasterhw.{p}" for p in found]


_BUILD = tempfile.mkdtemp(prefix="rasterhw-build-")
atexit.register(shutil.rmtree, _BUILD, ignore_errors=True)

setup(version=VERSION, packages=_packages(), cmdclass={"build_py": BuildPy},
      options={"build": {"build_base": _BUILD}, "egg_info": {"egg_base": _BUILD}})
