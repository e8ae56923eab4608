"""Compare the EXPERTS blocks' elaborated designs with a base commit's (a refactor's check).

``python tests/experts/netlist_check.py --base COMMIT`` converts each block below with
``amaranth.back.rtlil.convert`` in this tree and in ``git archive COMMIT`` (unpacked to a temporary
folder), strips the ``src`` attributes (file and line numbers) and says, per configuration, whether
the RTLIL is identical; exit 1 if any differs. ``--dump`` prints this tree's digests as JSON.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

#: (name, module, class, keyword arguments): each block at its defaults and at the paper's datapath
CONFIGS = [
    ("slp", "slp", "ExpertsSlp", {}),
    ("slp-paper", "slp", "ExpertsSlp", {"acc_extra": 0}),
    ("slp-small", "slp", "ExpertsSlp", {"width": 64, "lines": 32, "guard": 0}),
    # the place-and-route records' SLP (docs/reproduction/fpga_runs.json), at both datapaths
    ("slp-fpga", "slp", "ExpertsSlp", {"asl": 64, "lines": 32, "tris": 64, "width": 64}),
    ("slp-fpga-paper", "slp", "ExpertsSlp", {"asl": 64, "lines": 32, "tris": 64, "width": 64, "acc_extra": 0}),
    ("slp-setup", "slp_setup", "ExpertsSlpSetup", {}),
    ("slp-setup-paper", "slp_setup", "ExpertsSlpSetup", {"acc_extra": 0}),
    ("pxp", "pxp", "ExpertsPxp", {}),
    ("pxp-c", "pxp", "ExpertsPxp", {"aj": "c", "intensity_bits": 4}),
    ("pxp-coherent", "pxp_coherent", "ExpertsPxpCoherent", {}),
    ("pxp-coherent-c", "pxp_coherent", "ExpertsPxpCoherent", {"aj": "c"}),
    ("dmm", "dmm", "ExpertsDmm", {}),
    ("group", "group", "ExpertsGroup", {}),
    ("group-small", "group", "ExpertsGroup", {"width": 64, "pn": 2, "aj": "none", "lines": 16}),
    ("unit", "unit", "ExpertsPxpUnit", {}),
    ("pxp-span", "pxp_span", "ExpertsPxpSpan", {}),
    ("pxp-span-c", "pxp_span", "ExpertsPxpSpan", {"aj": "c"}),
    ("pxp-span-paper", "pxp_span", "ExpertsPxpSpan", {"datapath": "paper"}),
    ("pxp-span-paper-c", "pxp_span", "ExpertsPxpSpan", {"aj": "c", "datapath": "paper"}),
    ("pxp-coherent-paper", "pxp_coherent", "ExpertsPxpCoherent", {"datapath": "paper"}),
    ("pxp-coherent-paper-c", "pxp_coherent", "ExpertsPxpCoherent", {"aj": "c", "datapath": "paper"}),
]

_SRC = re.compile(r"^\s*attribute \\src .*\n", re.MULTILINE)


def rtlil(module: str, cls: str, kw: dict) -> str:
    import importlib

    from amaranth.back import rtlil as back
    mod = importlib.import_module(f"rasterhw.hdl.experts.{module}")
    return _SRC.sub("", back.convert(getattr(mod, cls)(**kw)))


def dump(out: Path | None) -> dict:
    digests = {}
    for name, module, cls, kw in CONFIGS:
        try:
            text = rtlil(module, cls, kw)
        except (TypeError, ValueError):     # a configuration this code refuses (the base's, before it was built)
            continue
        digests[name] = hashlib.sha256(text.encode()).hexdigest()
        if out is not None:
            (out / f"{name}.il").write_text(text)
    return digests


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", help="commit to compare with")
    ap.add_argument("--dump", action="store_true", help="print this tree's digests as JSON")
    ap.add_argument("--out", type=Path, help="also write each stripped RTLIL to OUT/NAME.il")
    a = ap.parse_args(argv)
    if a.out:
        a.out.mkdir(parents=True, exist_ok=True)
    if a.dump or not a.base:
        print(json.dumps(dump(a.out), indent=1))
        return 0
    tree = Path(__file__).resolve().parents[2]
    with tempfile.TemporaryDirectory() as tmp:
        pkg = Path(tmp) / "rasterhw"
        pkg.mkdir()
        arc = subprocess.run(["git", "-C", str(tree), "archive", a.base], check=True, capture_output=True).stdout
        tar = Path(tmp) / "base.tar"
        tar.write_bytes(arc)
        with tarfile.open(tar) as t:
            t.extractall(pkg, filter="data")
        # this tree's list of configurations, on the base's code (a configuration the base refuses is new)
        cmd = [sys.executable, __file__, "--dump"]
        if a.out:
            cmd += ["--out", str(a.out / "base")]
        env = dict(os.environ, PYTHONPATH=tmp)
        base = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout)
    ours = dump(a.out)
    bad = 0
    for name in ours:
        if name not in base:
            print(f"{name:18s} new (the base refuses it)  {ours[name][:16]}")
            continue
        same = ours[name] == base[name]
        bad += not same
        print(f"{name:18s} {'same' if same else 'DIFFERS'}  {ours[name][:16]}  base {base[name][:16]}")
    both = sum(name in base for name in ours)
    print(f"{both - bad}/{both} configurations identical to {a.base}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
