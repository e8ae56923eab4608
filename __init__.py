"""rasterhw: RTL-style models of parallel 3-D rendering machines, checked against a golden model."""

__version__ = "0.1.0"
