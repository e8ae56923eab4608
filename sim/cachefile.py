"""Cache entries that prove what they hold: the one reader and writer of every file the build
cache (``sim/paths.py: BUILD_ROOT``) keeps for reuse.

* :func:`write_entry` writes a cache file whole or not at all (a temporary file beside it, then a
  rename), *replacing* a symbolic link found at its name instead of writing through it, and only
  inside the cache folder (a folder on the way that leads elsewhere is an error); it records the
  file's SHA-256 beside it (``NAME.sha256``);
* :func:`read_entry` gives a cache file's bytes only when they match that record: an entry
  truncated, edited or replaced since it was written is said in one line on stderr, removed, and
  comes back as ``None`` (the caller rebuilds it once); an entry without a record (written before
  records were kept, or interrupted between the two writes) is ``None`` silently;
* :func:`sha256_file` and :func:`matches` check the files a build folder's own record names (a
  Verilator binary: ``build.json``; a gcc profile: ``trained.json``);
* :func:`check_writable` says, before any work, that the cache cannot be written (instead of after
  minutes of elaboration, when the first entry is stored);
* :func:`mark_used` stamps the cache entry holding a file with the time it was used (its folder's
  modification time; a file entry's record): :func:`read_entry` and :func:`matches` call it on
  every hit, so ``rasterhw cache clean`` (``sim/cacheinfo.py``) removes the least recently *used*
  entries first, not the oldest built; :func:`entry_of` says which entry a file belongs to.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.paths import BUILD_ROOT, umask

__all__ = ["NESTED", "RECORD_SUFFIX", "check_writable", "entry_of", "inside_cache", "mark_used", "matches",
           "read_entry", "sha256_file", "warn_damaged", "write_entry"]

#: the record of an entry's SHA-256 is the entry's name with this added
RECORD_SUFFIX = ".sha256"

#: folders of the cache whose entries lie deeper than its top level: folder -> how many levels
#: below it one entry is (``verilog/NAME-DIGEST.v``; ``tasks/AB/DIGEST.json``); every other
#: top-level file or folder of the cache is one entry
NESTED = {"verilog": 1, "zbm-verilog": 1, "verilator-runtime": 1, "pgo": 1, "tasks": 2}

#: digests already computed in this process, by (path, inode, size, mtime): a soak's thousand
#: runs of one binary hash it once
_DIGESTS: dict[tuple, str] = {}


def sha256_file(path: str | Path) -> str:
    """SHA-256 (hex) of the file at ``path`` (read in 1 MB pieces)."""
    st = os.stat(path)
    key = (str(path), st.st_ino, st.st_size, st.st_mtime_ns)
    if key not in _DIGESTS:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            while chunk := f.read(1 << 20):
                h.update(chunk)
        _DIGESTS[key] = h.hexdigest()
    return _DIGESTS[key]


def _record(path: Path) -> Path:
    return path.with_name(path.name + RECORD_SUFFIX)


def inside_cache(path: str | Path, root: str | Path | None = None) -> Path:
    """``path`` if the folder it is in, with every symbolic link on the way resolved, lies in the
    cache folder ``root`` (default ``BUILD_ROOT``); else a :class:`RasterhwError` (a planted link
    would make a cache write land outside the cache)."""
    path = Path(path)
    top = Path(os.path.realpath(root if root is not None else BUILD_ROOT))
    where = Path(os.path.realpath(path.parent))
    if where != top and top not in where.parents:
        raise RasterhwError(f"cache file {path}: its folder leads to {where}, outside the cache folder {top} "
                            "(a symbolic link?); remove the link")
    return path


def _replace(path: Path, data: bytes) -> None:
    """Put ``data`` at ``path`` atomically; a link at ``path`` is replaced, not followed."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o666 & ~umask())
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def write_entry(path: str | Path, data: bytes, *, root: str | Path | None = None) -> str:
    """Write cache entry ``path`` (see the module docstring) and its SHA-256 record; return the digest."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    inside_cache(path, root)
    digest = hashlib.sha256(data).hexdigest()
    _replace(path, data)
    _replace(_record(path), (digest + "\n").encode())
    return digest


def warn_damaged(path: str | Path, what: str) -> None:
    """The one line said when a cache entry does not match its record."""
    print(f"warning: {what} in the cache ({path}) does not match the SHA-256 recorded when it was written "
          "(truncated or edited); rebuilding it", file=sys.stderr)


def read_entry(path: str | Path, *, what: str) -> bytes | None:
    """The bytes of cache entry ``path`` if they match their record, else ``None`` (see the module
    docstring; a mismatch is said on stderr as :func:`warn_damaged` and the entry removed)."""
    path = Path(path)
    try:
        want = _record(path).read_text().strip()
        data = path.read_bytes()
    except (OSError, UnicodeDecodeError):
        return None
    if hashlib.sha256(data).hexdigest() != want:
        warn_damaged(path, what)
        for f in (path, _record(path)):
            f.unlink(missing_ok=True)
        return None
    mark_used(path)
    return data


def matches(path: str | Path, digest: str | None, *, what: str, quiet: bool = False) -> bool:
    """Does the file at ``path`` exist and have SHA-256 ``digest``? A file that exists with another
    digest is said on stderr (:func:`warn_damaged`); no ``digest`` (an older record) is False, silently."""
    try:
        got = sha256_file(path)
    except OSError:
        return False
    if not digest:
        return False
    if got != digest:
        if not quiet:
            warn_damaged(path, what)
        return False
    mark_used(path)
    return True


def entry_of(path: str | Path, root: str | Path | None = None) -> Path | None:
    """The cache entry (a file or folder :func:`mark_used` stamps, ``rasterhw cache`` lists and
    removes) that ``path`` is in or is; None outside the cache folder ``root`` (default ``BUILD_ROOT``)."""
    top = Path(root if root is not None else BUILD_ROOT)
    try:
        rel = Path(path).relative_to(top)
    except ValueError:
        return None
    if not rel.parts:
        return None
    depth = 1 + NESTED.get(rel.parts[0], 0)
    return top.joinpath(*rel.parts[:depth]) if len(rel.parts) >= depth else None


def mark_used(path: str | Path) -> None:
    """Stamp the cache entry holding ``path`` as used now: a folder entry's modification time; a
    file entry's record (``NAME.sha256``) where it has one, so the entry's own bytes (and their
    digest, cached by modification time) are untouched. Quietly nothing where the cache is not ours
    to write (a shared read-only cache) or ``path`` lies outside it."""
    entry = entry_of(path)
    if entry is None:
        return
    if entry.is_file() and _record(entry).is_file():
        entry = _record(entry)
    try:
        os.utime(entry)
    except OSError:
        pass


def check_writable(folder: str | Path | None = None) -> Path:
    """``folder`` (default the cache folder) made if missing and proved writable by creating and
    removing a file in it; else one line naming it and ``RASTERHW_CACHE``."""
    folder = Path(folder if folder is not None else BUILD_ROOT)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".rasterhw-writable-", dir=folder)
        os.close(fd)
        os.unlink(tmp)
    except OSError as e:
        raise RasterhwError(f"the build cache {folder} cannot be written ({e.strerror or e}); "
                            "set RASTERHW_CACHE to a writable folder") from None
    return folder
