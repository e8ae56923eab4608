"""The ``rasterhw`` command line.

One BLAS thread unless the user says otherwise (``OPENBLAS_NUM_THREADS``), set here, before NumPy
is imported by the command's modules: OpenBLAS starts a thread per core when NumPy loads, ~0.05
CPU-s per command on a 2-core machine (``python -c "import numpy"``: 0.11 CPU-s, 0.06 with one
thread), for nothing: the package's linear algebra is on 3 x 3 and 4 x 4 matrices, where a second
thread does not help (``docs/speed.md``, "Issue 51 (engineer 46r)"). The cocotb ZB/M bench's simulator process
does the same (``tests/zbm_cocotb/unit_bench.py: SIM_ENV``)."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
