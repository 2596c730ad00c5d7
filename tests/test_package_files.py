"""The files a package carries besides its code: LICENSE, CHANGELOG.md,
CITATION.cff and the index of docs/ (issue 18, item 4)."""
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_license_is_the_full_text_of_the_license_pyproject_names():
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"]["text"] == "GPL-3.0-or-later"
    text = (ROOT / "LICENSE").read_text()
    assert text.lstrip().startswith("GNU GENERAL PUBLIC LICENSE")
    assert "Version 3, 29 June 2007" in text
    assert "END OF TERMS AND CONDITIONS" in text  # the full text, not a notice
    assert len(text.splitlines()) > 600


def test_citation_cff_has_the_required_keys_and_cites_the_seed_paper():
    yaml = pytest.importorskip("yaml")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    for key in ("cff-version", "message", "title", "authors"):
        assert cff.get(key), key
    assert cff["cff-version"] == "1.2.0"
    assert all(isinstance(a, dict) and ("name" in a or "family-names" in a) for a in cff["authors"])
    assert cff["license"] == "GPL-3.0-or-later"
    tomllib = pytest.importorskip("tomllib")
    assert str(cff["version"]) == tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    seed = [r for r in cff["references"] if r["title"] == "Phase-fitted Discrete Lagrangian Integrators"]
    assert len(seed) == 1
    assert [a["family-names"] for a in seed[0]["authors"]] == ["Kosmas", "Vlachos"]


def test_changelog_opens_with_unreleased():
    headings = [line for line in (ROOT / "CHANGELOG.md").read_text().splitlines() if line.startswith("## ")]
    assert headings and headings[0] == "## Unreleased"


def _links(path):
    return set(re.findall(r"\]\(([^)#\s]+)", path.read_text()))


def test_docs_index_links_every_page_and_nothing_missing():
    docs = ROOT / "docs"
    links = _links(docs / "README.md")
    pages = {p.name for p in docs.glob("*.md") if p.name != "README.md"}
    assert pages, "no pages in docs/"
    assert pages <= links, f"not linked from docs/README.md: {sorted(pages - links)}"
    broken = sorted(link for link in links if not (docs / link).is_file())
    assert not broken, f"docs/README.md links to missing files: {broken}"
