"""CITATION.cff (issue 53 item 5): valid CFF 1.2 with the release's version and a release date,
so a BibTeX entry made from it (cffconvert) has the year; the version equals the package's."""

from __future__ import annotations

import datetime
import tomllib
from pathlib import Path

import pytest
import yaml
from rasterhw import __version__

ROOT = Path(__file__).resolve().parents[1]


def test_citation_names_the_release_and_its_date():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert str(cff["version"]) == __version__
    assert datetime.date.fromisoformat(str(cff["date-released"])).year >= 2026
    # an address, once the project has one, is the same in both files
    urls = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"].get("urls", {})
    assert cff.get("url") in (None, *urls.values()) and (cff.get("url") is None) == (not urls)


def test_bibtex_from_the_citation_has_the_year():
    """Where cffconvert is installed (it is not a dependency: its 2.0.0 pins old libraries). Its
    BibTeX has no version field at all; its APA line has the version."""
    conv = pytest.importorskip("cffconvert.cli.create_citation")
    cit = conv.create_citation(str(ROOT / "CITATION.cff"), None)
    assert "year = {2026}" in cit.as_bibtex()
    assert f"(version {__version__})" in cit.as_apalike()
