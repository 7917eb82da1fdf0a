"""The docs site: ``mkdocs build --strict`` of ``mkdocs.yml`` succeeds, and fails on a warning;
and its gallery: the example notebooks (``docs/examples/*.ipynb``) run from top to bottom
without error, and every cell that draws a figure shows it as an image (as in Jupyter: a fresh
kernel, the inline backend, no ``%matplotlib`` magic).

The tools (mkdocs, mkdocs-material, mkdocstrings[python]) are in the ``test`` extra, so a
missing one is an error here, not a skip. The build runs offline: nothing in the configuration
fetches anything (the theme's web fonts are off).

The notebooks' tests come first in this file and store each executed notebook where the site's
gallery (``mkdocs_hooks.py``) picks it up, so the site build after them does not execute them
again (2 min of the suite on 2 cores with a fresh cache; they were two files, which
``--dist loadfile`` could run on two workers side by side, each executing every notebook).
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "docs" / "examples").glob("*.ipynb"))

#: a cell draws a figure when it calls one of these (the package's figures, pyplot's show)
PLOTTING = re.compile(
    r"\.plot\(|\b(heatmap_figure|map_figure|result_figure|compare_figure|detuning_figure)\(|"
    r"plt\.show\(\)"
)


# ------------------------------------------------------------------------------------------
# the gallery's notebooks (before the site build, which reuses their execution)


def _nbformat():
    """nbformat, the notebooks' tests skipping where the kernel's tools are missing."""
    pytest.importorskip("nbclient", reason="the test extra installs nbclient")
    pytest.importorskip("ipykernel", reason="the test extra installs ipykernel")
    return pytest.importorskip("nbformat", reason="the test extra installs nbformat")


def _hooks():
    spec = importlib.util.spec_from_file_location("mkdocs_hooks", ROOT / "mkdocs_hooks.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 6


def test_every_notebook_draws_a_figure():
    nbformat = _nbformat()
    for path in NOTEBOOKS:
        nb = nbformat.read(path, as_version=4)
        assert any(PLOTTING.search(c.source) for c in nb.cells if c.cell_type == "code"), path


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_and_shows_its_figures(path):
    _nbformat()
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


# ------------------------------------------------------------------------------------------
# the site


def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)]
    return subprocess.run(
        cmd, cwd=config.parent, env=env, capture_output=True, text=True, timeout=600
    )


def _config() -> dict:
    return yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=yaml.SafeLoader)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_site_builds_strict_with_every_page_and_the_api_reference(tmp_path):
    site = tmp_path / "site"
    proc = _build(ROOT / "mkdocs.yml", site)
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log
    assert "WARNING" not in log, log
    # every page of docs/ is in the nav and built
    for md in (ROOT / "docs").rglob("*.md"):
        page = site / md.relative_to(ROOT / "docs").with_suffix(".html")
        assert page.is_file(), f"{md} was not built"
    nav = yaml.dump(_config()["nav"])
    for md in (ROOT / "docs").rglob("*.md"):
        assert md.relative_to(ROOT / "docs").as_posix() in nav, f"{md.name} is not in the nav"
    # the notebooks are published beside the page that links them
    for nb in (ROOT / "docs" / "examples").glob("*.ipynb"):
        assert (site / "examples" / nb.name).is_file()
    # the gallery: each notebook executed as a page of the site, with its figures
    for nb in (ROOT / "docs" / "examples").glob("*.ipynb"):
        page = site / "examples" / f"{nb.stem}.html"
        assert page.is_file(), f"no gallery page for {nb.name}"
        images = re.findall(rf'<img[^>]+src="({re.escape(nb.stem)}-\d+\.png)"', page.read_text())
        assert images, f"the gallery page of {nb.name} shows no figure"
        for name in images:
            assert (site / "examples" / name).stat().st_size > 5000, name
    # a gallery page as a browser draws it: the page and its figure, not a blank page
    from data.browser import assert_nonblank, find_chromium, screenshot

    if find_chromium() is not None:
        page = site / "examples" / "01-quick-start.html"
        pixels = screenshot(page, tmp_path / "gallery.png", width=1200, height=2400)
        assert_nonblank(pixels, min_colours=200)  # a figure has many more colours than text
    # the API reference is generated from the docstrings, with the numpydoc sections
    api = (site / "api" / "simulate.html").read_text()
    assert 'id="imdrive.run.simulate.simulate"' in api
    assert "Signals (units in the column names)" in api  # simulate's Returns description
    # SimulationResult.window's Parameters table
    assert re.search(r"<td>\s*<code>t0</code>\s*</td>.*Start of the window, s\.", api, re.S)
    # no Sphinx role is left as text, and the site fetches no web font
    for page in site.rglob("*.html"):
        html = page.read_text()
        assert not re.search(r":(func|class|meth|mod|attr|data|exc):<code>", html), page
        assert "fonts.googleapis.com" not in html, page


def _mini_project(tmp_path: Path, page: str, module: str = "") -> Path:
    """A project with the repository's settings (strict, link validation, the hook, the
    docstring handler), one page and optionally one Python module to document."""
    cfg = _config()
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "index.md").write_text(textwrap.dedent(page))
    src = tmp_path / "src"
    src.mkdir()
    if module:
        (src / "dummy.py").write_text(textwrap.dedent(module))
    cfg["docs_dir"] = str(docs)
    cfg["nav"] = [{"Home": "index.md"}]
    cfg["hooks"] = [str(ROOT / "mkdocs_hooks.py")]
    for plugin in cfg["plugins"]:
        if isinstance(plugin, dict) and "mkdocstrings" in plugin:
            plugin["mkdocstrings"]["handlers"]["python"]["paths"] = [str(src)]
    config = tmp_path / "mkdocs.yml"
    config.write_text(yaml.dump(cfg))
    return config


RIGHT_MODULE = '''\
    def scale(x_s: float) -> float:
        """Scale a time.

        Parameters
        ----------
        x_s : float
            A time, s.

        Returns
        -------
        float
            Twice ``x_s``, s.
        """
        return 2 * x_s
    '''


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_a_link_to_a_repository_file_becomes_its_path_and_a_missing_one_fails(tmp_path):
    """Also the passing half of the docstring pair below: the mini site with ``dummy.scale``
    documented right builds (a build of its own before, 4-7 s)."""
    page = (
        "# Home\n\nThe layer rules: [the layer test](../tests/test_layers.py).\n\n"
        "See [below](#dummy.scale).\n\n::: dummy.scale\n"
    )
    config = _mini_project(tmp_path, page, RIGHT_MODULE)
    proc = _build(config, tmp_path / "site")
    assert proc.returncode != 0  # tests/test_layers.py is not in the mini project
    assert "test_layers.py" in proc.stdout + proc.stderr
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_layers.py").write_text("")
    proc = _build(config, tmp_path / "site")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    html = (tmp_path / "site" / "index.html").read_text()
    assert "the layer test (<code>tests/test_layers.py</code>)" in html
    # the mini site of the docstring test below, with its docstring right: it builds
    assert 'id="dummy.scale"' in html


@pytest.mark.slow  # 1.5 s or more on 2 cores (5.8 s measured 2026-11-29)
def test_strict_build_fails_on_a_broken_link_and_on_a_broken_anchor(tmp_path):
    """One build of a page with both (a build per fault was 4-6 s each): each is a warning
    of its own, and --strict fails on any one warning."""
    page = "# Home\n\nSee [the missing page](missing.md).\n\nSee [below](#no-such-heading).\n"
    proc = _build(_mini_project(tmp_path, page), tmp_path / "site")
    log = proc.stdout + proc.stderr
    assert proc.returncode != 0
    warnings = [line for line in log.splitlines() if line.startswith("WARNING")]
    assert len(warnings) == 2, log
    assert any("'missing.md'" in w for w in warnings), log
    assert any("'#no-such-heading'" in w for w in warnings), log
    assert "Aborted with 2 warnings in strict mode" in log


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_strict_build_fails_on_a_docstring_that_does_not_match_its_signature(tmp_path):
    """Its twin with the docstring right (RIGHT_MODULE) builds: the repository-link test."""
    module = '''\
        def scale(x_s: float) -> float:
            """Scale a time.

            Parameters
            ----------
            y_s : float
                A parameter the function does not have, s.

            Returns
            -------
            float
                Twice ``x_s``, s.
            """
            return 2 * x_s
        '''
    config = _mini_project(tmp_path, "# Home\n\n::: dummy.scale\n", module)
    proc = _build(config, tmp_path / "site")
    assert proc.returncode != 0
    assert "y_s" in proc.stdout + proc.stderr
