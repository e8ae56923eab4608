"""Generated Verilog cached on disk by a digest of the design's parameters and source.

``amaranth.back.verilog.convert`` of a large block takes tens of seconds (the sparse video
processor ~25 s, the ZB/M unit more); a scene run whose Verilator model is already built
should not pay it again. :func:`convert_cached` keys the text on the block name, its
parameters, the Amaranth version and the bytes of every Python file the design can depend on
(:func:`design_sources`: ``hdl/``, the generator and every module of ours they import, such as
the formats modules the HDL takes its widths from), so any change to the design gives a fresh
conversion and an unchanged design never converts twice.
Files go to ``build/verilog/<name>-<digest>.v``, written atomically, each with the SHA-256 of its
text beside it (``sim/cachefile.py``): a truncated or edited entry is said in one line and converted
again, never served.
"""

from __future__ import annotations

import ast
import hashlib
import json
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from functools import cache
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cachefile import check_writable, read_entry, write_entry
from rasterhw.sim.engines.verilog import canonical_port_lists, generate_verilog
from rasterhw.sim.outfile import write_text
from rasterhw.sim.paths import BUILD_ROOT, REPO_ROOT
from rasterhw.sim.registry import blocks

__all__ = ["amaranth_version", "arrays_cached", "closure_cached", "fields_key", "convert_cached", "factory_params", "design_sources", "generate_cached", "module_sources", "source_digest", "sources_digest",
           "write_verilog"]

PKG_ROOT = REPO_ROOT


def _module_file(mod: str) -> Path | None:
    """The file of module ``rasterhw.<...>`` (a package's ``__init__.py``), None if not ours."""
    parts = mod.split(".")
    if parts[0] != "rasterhw":
        return None
    base = PKG_ROOT.joinpath(*parts[1:])
    for f in (base.with_suffix(".py"), base / "__init__.py"):
        if f.is_file():
            return f
    return None


def _imported_files(f: Path) -> set[Path]:
    """Our modules that ``f`` imports (anywhere in it: lazy imports count), by name: for
    ``from pkg import name`` the submodule ``pkg.name`` if it is one, else ``pkg``; a relative
    import (``from .helper import x``) is the file beside ``f`` it names."""
    st = f.stat()
    return _imports_of(f, st.st_mtime_ns, st.st_size)


#: CPython 3.11's parser keeps one recursion-depth count per interpreter: two threads parsing at
#: once (the sparse matrix's processors build their benches from a thread pool) can fail with
#: "SystemError: AST constructor recursion depth mismatch" (seen in a test run); one parse at a time
_PARSE_LOCK = threading.Lock()


@cache
def _imports_of(f: Path, _mtime_ns: int, _size: int) -> frozenset[Path]:
    """:func:`_imported_files` of ``f`` as it is at this modification time and size (parsed once)."""
    out: set[Path] = set()
    with _PARSE_LOCK:
        tree = ast.parse(f.read_bytes(), str(f))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {m for m in (_module_file(a.name) for a in node.names) if m is not None}
        elif isinstance(node, ast.ImportFrom) and node.level:
            base = f.parent
            for _ in range(node.level - 1):
                base = base.parent
            if node.module:
                base = base.joinpath(*node.module.split("."))
            for a in node.names:
                hit = _file_at(base / a.name) or _file_at(base)
                if hit is not None:
                    out.add(hit)
        elif isinstance(node, ast.ImportFrom) and node.module:
            for a in node.names:
                m = _module_file(f"{node.module}.{a.name}") or _module_file(node.module)
                if m is not None:
                    out.add(m)
    return frozenset(out)


def _file_at(base: Path) -> Path | None:
    """The module at ``base`` (``base.py`` or a package's ``base/__init__.py``), None if neither."""
    for f in (base.with_suffix(".py"), base / "__init__.py"):
        if f.is_file():
            return f
    return None


def module_sources(roots: Iterable[Path]) -> list[Path]:
    """The Python files ``roots`` and, transitively, every module of ours they import (anywhere in
    a module: imports inside functions count), with the ``__init__.py`` of every package of ours
    on the way (importing a module runs them). Ours: ``rasterhw.*`` under the package root, and
    what a relative import names. The one rule of every cache key on Python sources here:
    :func:`design_sources` (a block's Verilog) and the Verilator engine's bench tops."""
    todo = [Path(r).resolve() for r in roots]
    seen: set[Path] = set()
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        todo += sorted(_imported_files(f) - seen)
    # importing a module runs its packages' __init__ files too: their bytes count, but what they
    # import for convenience (a package's whole golden model) does not reach the HDL
    inits = {d / "__init__.py" for f in seen for d in f.parents
             if PKG_ROOT in (d, *d.parents) and (d / "__init__.py").is_file()}
    return sorted(seen | inits)


def _stamp(f: Path) -> list[int]:
    st = f.stat()
    return [st.st_mtime_ns, st.st_size]


def closure_cached(roots: list[Path], store: Path) -> list[Path]:
    """:func:`module_sources` of ``roots``, kept in a cache entry of its own per set of roots,
    ``<store>-<digest of the roots>.json`` (``store``: a path in the build cache without the suffix,
    e.g. ``build/verilog/design-sources``), written and read through ``cachefile.write_entry`` /
    ``read_entry`` (SHA-256 checked: a damaged entry is said in one line and found again, never
    served; parsing ~50 modules for their imports cost ~0.3 CPU-s a run). Reused while no file of
    the closure and no folder holding one has changed (a file edited, added or removed there
    changes its stamp), else found again. The closure depends only on those files' text and on
    which modules exist."""
    key = "|".join(str(Path(r).resolve()) for r in roots)
    path = store.with_name(f"{store.name}-{hashlib.sha1(key.encode()).hexdigest()[:16]}.json")
    raw = read_entry(path, what="an index of Python sources")
    try:
        hit = json.loads(raw) if raw is not None else None
        if hit is not None and hit["roots"] == key and all(_stamp(Path(f)) == st for f, st in hit["stamps"].items()):
            return [Path(f) for f in hit["files"]]
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        pass   # a file of the closure gone, or an entry of another shape: found again
    files = module_sources(roots)
    stamps = {str(f): _stamp(f) for f in files} | {str(d): _stamp(d) for d in {f.parent for f in files}}
    try:
        write_entry(path, json.dumps({"roots": key, "files": [str(f) for f in files], "stamps": stamps}).encode())
    except (OSError, RasterhwError):
        pass   # a read-only cache (or a link planted on the way): found again next time
    return files


def sources_digest(files: Iterable[Path]) -> str:
    """Digest of the Amaranth version and the names and bytes of ``files`` (ours by their path in
    the package, so a checkout elsewhere gives the same digest; others by their file name)."""
    h = hashlib.sha1(amaranth_version().encode())
    for f in files:
        h.update(str(f.relative_to(PKG_ROOT) if PKG_ROOT in f.parents else f.name).encode())
        h.update(f.read_bytes())
    return h.hexdigest()


@cache
def amaranth_version() -> str:
    """``amaranth.__version__`` without importing Amaranth (its package metadata, as Amaranth reads
    it; ``"unknown"`` without any): a cached design is found with no Amaranth import. The one
    ``amaranth-*.dist-info`` beside the package Python would import is read directly (importing
    ``importlib.metadata`` and searching every path entry cost ~0.05 CPU-s of each warm run);
    anything else (none there, or several) asks ``importlib.metadata``."""
    import importlib.util

    spec = importlib.util.find_spec("amaranth")
    if spec is not None and spec.origin:
        found = list(Path(spec.origin).parent.parent.glob("amaranth-*.dist-info/METADATA"))
        if len(found) == 1:
            for line in found[0].read_text(errors="replace").splitlines():
                if line.startswith("Version:"):
                    return line.split(":", 1)[1].strip()
                if not line:   # the headers end at the first empty line
                    break
    import importlib.metadata

    try:
        return importlib.metadata.version("amaranth")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


def fields_key(obj) -> list:
    """An object's fields as :func:`arrays_cached` key items: name, value, name, value, ... sorted by
    name (e.g. a scene's screen triangles: every array by its bytes)."""
    return [x for k, v in sorted(vars(obj).items()) for x in (k, v)]


def arrays_cached(name: str, sources: Path, key: Sequence, compute: Callable[[], dict[str, np.ndarray]]
                  ) -> dict[str, np.ndarray]:
    """``compute()`` (a golden model's result: named NumPy arrays) kept as a build-cache entry
    ``build/verilog/<name>-<digest>.npz`` (SHA-256 checked through ``cachefile.read_entry`` /
    ``write_entry``; read without pickle), keyed by ``key`` (the inputs: arrays by their bytes,
    dtype and shape; anything else by its JSON) and the digest of ``sources`` and every module of
    ours it imports, transitively (:func:`closure_cached`): an edit to the model computes it again.
    The entry holds its whole digest (its name only the first 64 bits): an entry of another key
    under the same name is computed again, never served. For a result that costs more than reading
    it back (``rasterhw sim pixelbus``: the pixel bus's accept cycles, 0.15-0.28 CPU-s a run;
    ``rasterhw sim pxp``: a scene's golden PXP jobs, ~1 CPU-s)."""
    import io

    h = hashlib.sha1(sources_digest(closure_cached([sources], BUILD_ROOT / "verilog" / "model-sources")).encode())
    for v in key:
        if isinstance(v, np.ndarray):
            h.update(str((v.dtype.str, v.shape)).encode() + np.ascontiguousarray(v).tobytes())
        else:
            h.update(json.dumps(v, sort_keys=True, default=str).encode())
        h.update(b"\0")
    digest = np.frombuffer(h.hexdigest().encode(), np.uint8)
    path = BUILD_ROOT / "verilog" / f"{name}-{h.hexdigest()[:16]}.npz"
    raw = read_entry(path, what=f"a cached result of {name}")
    if raw is not None:
        with np.load(io.BytesIO(raw), allow_pickle=False) as z:
            got = {k: z[k] for k in z.files}
        if np.array_equal(got.pop(_DIGEST, None), digest):
            return got
    out = {k: np.asarray(v) for k, v in compute().items()}
    buf = io.BytesIO()
    np.savez(buf, **out, **{_DIGEST: digest})
    try:
        write_entry(path, buf.getvalue())
    except (OSError, RasterhwError):
        pass   # a read-only cache: computed again next time
    return out


#: the array of an :func:`arrays_cached` entry that holds its key's whole digest
_DIGEST = "__digest__"


def design_sources(block: str | None = None) -> list[Path]:
    """Every Python file the generated Verilog of ``block`` (a ``rasterhw verilog --list`` name)
    can depend on: the module of its factory, the Verilog generator (``sim/engines/verilog.py``) and,
    transitively, every module of ours they import (its HDL submodules, the formats modules in
    ``golden_model/`` the HDL takes its widths from; :func:`module_sources`), and nothing else, so
    an edit to another block or to a golden algorithm does not regenerate (or rebuild) it.
    ``block=None`` (or a name that is not a registered block): all of ``hdl/`` as the roots."""
    ref = blocks().get(block) if block else None
    root = _module_file(ref.split(":")[0]) if ref else None
    roots = [root] if root is not None else sorted((PKG_ROOT / "hdl").rglob("*.py"))
    return closure_cached([*roots, PKG_ROOT / "sim" / "engines" / "verilog.py"], _DESIGN_CLOSURES)


#: :func:`design_sources` of each block, with every file's and folder's stamp (:func:`closure_cached`):
#: ``build/verilog/design-sources-<digest>.json``, one per block
_DESIGN_CLOSURES = BUILD_ROOT / "verilog" / "design-sources"


def factory_params(block: str) -> tuple[list[str], dict]:
    """(parameter names, defaults) of registered block ``block``'s factory, kept in
    ``build/verilog/<block>-params-<digest>.json`` by :func:`source_digest` (every file the factory
    can depend on), so a run with a cached design never imports the HDL (nor Amaranth) to read a
    signature. Defaults that JSON does not give back as they were (a tuple, an object) are not kept:
    the factory is then imported each time."""
    import inspect

    from rasterhw.sim.registry import load

    path = BUILD_ROOT / "verilog" / f"{block}-params-{source_digest(block)[:16]}.json"
    got = read_entry(path, what=f"the parameters of {block}")
    if got is not None:
        names, defaults = json.loads(got)
        return names, defaults
    sig = inspect.signature(load(blocks()[block]))
    names = list(sig.parameters)
    defaults = {k: v.default for k, v in sig.parameters.items() if v.default is not inspect.Parameter.empty}
    try:
        text = json.dumps([names, defaults])
        if json.loads(text) == [names, defaults] and all(type(v) in (int, float, str, bool, type(None))
                                                         for v in defaults.values()):
            write_entry(path, text.encode(), root=BUILD_ROOT)
    except (TypeError, ValueError, OSError):
        pass   # not kept: read from the factory next time
    return names, defaults


@cache
def source_digest(block: str | None = None) -> str:
    """Digest of the Amaranth version and every file of :func:`design_sources` (once per process)."""
    return sources_digest(design_sources(block))


def convert_cached(name: str, factory: Callable[[], object], *, params: Mapping[str, object],
                   module: str, convert: Callable[[object, str], str] | None = None) -> str:
    """Verilog text of ``factory()`` (an elaboratable) with top module ``module``.

    ``params`` must name everything the design depends on besides the source (the factory's
    arguments). ``convert(design, module)`` defaults to ``amaranth.back.verilog.convert``."""
    key = json.dumps({"name": name, "module": module, "params": dict(params)}, sort_keys=True, default=str)
    digest = hashlib.sha1((source_digest(name) + key).encode()).hexdigest()[:16]
    path = BUILD_ROOT / "verilog" / f"{name}-{digest}.v"
    got = read_entry(path, what=f"the generated Verilog of {name}")
    if got is not None:
        return got.decode()
    check_writable(path.parent)   # an unwritable cache is said now, not after the elaboration
    if convert is None:
        def convert(design, mod):
            from amaranth.back import verilog

            return canonical_port_lists(verilog.convert(design, name=mod))
    text = convert(factory(), module)
    write_entry(path, text.encode(), root=BUILD_ROOT)
    return text


def generate_cached(block: str, **params) -> str:
    """``rasterhw.sim.engines.verilog.generate_verilog(block, **params)``, cached like :func:`convert_cached`;
    keyed with the block's defaults filled in (:func:`effective_params`), so a parameter given at its
    default and one left out find the same entry."""
    return convert_cached(block, lambda: None, params=effective_params(block, params), module=block,
                          convert=lambda _design, _module: generate_verilog(block, **params))


def effective_params(name: str, params: Mapping[str, object]) -> dict:
    """``params`` with every parameter of block ``name``'s factory it leaves out at its default."""
    import inspect

    from rasterhw.sim.registry import load

    sig = inspect.signature(load(blocks()[name]))
    eff = {k: v.default for k, v in sig.parameters.items() if v.default is not inspect.Parameter.empty}
    eff.update(params)
    return eff


def write_verilog(name: str, path: str | Path, **params) -> Path:
    """Write :func:`generate_verilog` output to ``path`` (from the cache of generated Verilog,
    ``sim/engines/verilog_cache.py``, when this design and these parameters were converted before),
    under :func:`verilog_header`; return the path."""
    text = generate_cached(name, **params)
    return write_text(path, verilog_header(name, **params) + text)  # whole or not at all


def verilog_header(name: str, **params) -> str:
    """Comment lines that say what a generated file is: the block, every parameter (defaults
    filled in), the design digest (:func:`source_digest`), the rasterhw and Amaranth versions, and
    each port of the block's signature — a stream as one line with its payload's fields, in the
    flattened names the Verilog uses (``<port>__payload`` ...)."""
    from rasterhw.sim.engines.verilog import make_block
    from rasterhw.sim.version import version

    ours = version()   # the release and the commit (sim/version.py)
    eff = effective_params(name, params)
    given = " ".join(f"-p {k}={v}" for k, v in params.items())
    lines = [f"rasterhw {ours}: block {name} (rasterhw verilog {name}{' ' + given if given else ''})",
             "parameters: " + (", ".join(f"{k}={v}" for k, v in eff.items()) or "none"),
             f"design digest {source_digest(name)[:16]} (Amaranth {amaranth_version()}; every source file "
             "the block depends on)",
             f"top module {name.replace('-', '_')}; ports (in/out as seen by the block; besides them, clk and rst "
             "of each clock domain, e.g. merge_clk/merge_rst):"]
    lines += [f"  {p}" for p in port_lines(make_block(name, **params))]
    return "".join(f"// {ln}\n" for ln in lines) + "\n"


def port_lines(component) -> list[str]:
    """One line per port of ``component``'s signature; a stream (``valid``/``ready``/``payload``
    members under one path) as one line naming its payload's fields and widths."""
    from amaranth.hdl import Shape
    from amaranth.lib import data, wiring

    members = list(component.signature.members.flatten())
    ports = {path: m for path, m in members if m.is_port}
    streams = {path[:-1] for path in ports if path[-1] == "valid"
               and path[:-1] + ("ready",) in ports and path[:-1] + ("payload",) in ports}

    def vname(path):
        return "__".join(str(p) for p in path)

    def shape(m):
        sh = m.shape
        if isinstance(sh, data.Layout) or (isinstance(sh, type) and issubclass(sh, data.Struct)):
            lay = data.Layout.cast(sh)
            return "{" + ", ".join(f"{n}: {Shape.cast(f.shape).width}" for n, f in lay) + "}"
        return f"{Shape.cast(sh).width} bit{'s' if Shape.cast(sh).width != 1 else ''}"

    out = []
    for s in sorted(streams):
        flow = "in " if ports[s + ("valid",)].flow == wiring.In else "out"
        out.append(f"{flow} {vname(s)}: stream ({vname(s)}__valid/__ready/__payload), payload "
                   f"{shape(ports[s + ('payload',)])}")
    for path, m in ports.items():
        if path[:-1] in streams:
            continue
        out.append(f"{'in ' if m.flow == wiring.In else 'out'} {vname(path)}: {shape(m)}")
    return out
