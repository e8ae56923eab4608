"""``numba.njit(cache=True)`` for the fast paths, with a cache directory that works everywhere.

The fast modules (``reference_fast.py``, ``sparse/vpcycles_fast.py``) compile on first use and
cache on disk (``cache=True``): by default in ``__pycache__`` beside the module (numba's own
choice, which falls back to the user's cache directory, ``~/.cache/numba``, when the installed
package is read-only; ``NUMBA_CACHE_DIR`` overrides both). Where neither place is writable,
:func:`njit_cached` points numba at ``$TMPDIR/rasterhw-numba-UID`` and, failing that, compiles
without a cache.

This module imports numba at the top: only the fast modules import it, and they are loaded
through :class:`rasterhw.golden_model.fastpath.FastPath`, which falls back to the specification
where that fails.
"""

from __future__ import annotations

import os
import tempfile

import numba

__all__ = ["njit_cached"]


def njit_cached(fn):
    """``numba.njit(cache=True, nogil=True)``, with a cache directory of our own where numba
    finds no writable one (no ``__pycache__`` beside the module, no user cache directory)."""
    try:
        return numba.njit(cache=True, nogil=True)(fn)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        pass
    try:
        numba.config.CACHE_DIR = os.path.join(tempfile.gettempdir(), f"rasterhw-numba-{os.getuid()}")
        return numba.njit(cache=True, nogil=True)(fn)
    except (RuntimeError, OSError):
        return numba.njit(cache=False, nogil=True)(fn)
