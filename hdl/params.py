"""Read-only block parameters: ``@params("width", "interleave")`` on a block's class gives it a
property per name that reads ``self._NAME`` (set once in ``__init__``, where the parameter is
checked), so the blocks do not each repeat the same four-line property."""

from __future__ import annotations

from operator import attrgetter

__all__ = ["params"]


def params(*names: str):
    """Class decorator: a read-only property ``NAME`` backed by ``self._NAME`` for each name."""

    def add(cls):
        for name in names:
            setattr(cls, name, property(attrgetter("_" + name), doc=f"The block's ``{name}`` (read-only)."))
        return cls

    return add
