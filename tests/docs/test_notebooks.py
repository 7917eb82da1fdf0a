"""The example notebooks (``docs/examples/*.ipynb``) run from top to bottom without error, and
every cell that draws a figure shows it as an image (as in Jupyter: a fresh kernel, the inline
backend, no ``%matplotlib`` magic).

The executed notebooks are stored where the docs site's gallery (``mkdocs_hooks.py``) picks
them up, so a site build after the tests does not execute them again.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="the test extra installs nbformat")
nbclient = pytest.importorskip("nbclient", reason="the test extra installs nbclient")
pytest.importorskip("ipykernel", reason="the test extra installs ipykernel")

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "docs" / "examples").glob("*.ipynb"))

#: a cell draws a figure when it calls one of these (the package's figures, pyplot's show)
PLOTTING = re.compile(
    r"\.plot\(|\b(heatmap_figure|map_figure|result_figure|compare_figure|detuning_figure)\(|"
    r"plt\.show\(\)"
)


def _hooks():
    spec = importlib.util.spec_from_file_location("mkdocs_hooks", ROOT / "mkdocs_hooks.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 6


def test_every_notebook_draws_a_figure():
    for path in NOTEBOOKS:
        nb = nbformat.read(path, as_version=4)
        assert any(PLOTTING.search(c.source) for c in nb.cells if c.cell_type == "code"), path


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_and_shows_its_figures(path):
    hooks = _hooks()
    nb = hooks.execute_notebook(path, timeout=300)
    outputs = [(c, c.get("outputs", [])) for c in nb.cells if c.cell_type == "code"]
    errors = [o for _, outs in outputs for o in outs if o.get("output_type") == "error"]
    assert not errors, errors
    for cell, outs in outputs:
        if not PLOTTING.search(cell.source):
            continue
        pngs = [o["data"]["image/png"] for o in outs if "image/png" in o.get("data", {})]
        assert pngs, f"{path.name}: no image from the cell\n{cell.source}"
        assert all(len(p) > 5000 for p in pngs), f"{path.name}: a near-empty image"
    # no figure anywhere printed itself as text instead of showing
    for _, outs in outputs:
        for o in outs:
            data = o.get("data", {})
            if "<Figure size" in data.get("text/plain", ""):
                assert "image/png" in data, f"{path.name}: {data['text/plain']}"
    hooks.cache_executed(path, nb)  # the gallery of the docs site reuses it
