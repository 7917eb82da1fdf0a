"""Browser helpers of the report tests: find a headless Chromium, render a page's DOM, take a
screenshot and check it is not blank (``from data.browser import render``)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess

import numpy as np
import pytest

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome")


def find_chromium() -> str | None:
    """A Chromium-family browser: ``$IMDRIVE_CHROMIUM``, else the first on PATH."""
    given = os.environ.get("IMDRIVE_CHROMIUM")
    if given:
        return shutil.which(given)
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def render(path) -> str:
    """The DOM of ``path`` after its scripts ran, from headless Chromium (no network)."""
    browser = find_chromium()
    if browser is None:
        pytest.skip(
            "no Chromium found (tried $IMDRIVE_CHROMIUM and " + ", ".join(BROWSERS) + "): "
            "install Debian's chromium package to run the browser tests"
        )
    cmd = [
        browser,
        "--headless",
        "--no-sandbox",  # root in containers
        "--disable-gpu",
        "--no-first-run",
        "--proxy-server=127.0.0.1:9",  # any network fetch would fail (and show as an error)
        "--virtual-time-budget=30000",
        "--dump-dom",
        path.resolve().as_uri(),
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def _shot(path, out_png, width: int, height: int, dom: bool):
    """One start of headless Chromium (no network) that writes ``out_png``; with ``dom`` its
    stdout is the DOM after the scripts ran. Returns the completed process."""
    browser = find_chromium()
    if browser is None:
        pytest.skip("no Chromium found: install Debian's chromium package")
    cmd = [
        browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
        "--proxy-server=127.0.0.1:9", "--hide-scrollbars", "--virtual-time-budget=30000",
        f"--window-size={width},{height}", f"--screenshot={out_png}",
        *(["--dump-dom"] if dom else []), path.resolve().as_uri(),
    ]  # fmt: skip
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0 and out_png.is_file(), out.stderr[-2000:]
    return out


def screenshot(path, out_png, width: int = 1200, height: int = 2400):
    """A PNG of ``path`` as headless Chromium draws it (no network); returns its pixels
    (height x width x channels, floats in 0..1)."""
    import matplotlib.image

    _shot(path, out_png, width, height, dom=False)
    return matplotlib.image.imread(out_png)


def render_and_screenshot(path, out_png, width: int = 1200, height: int = 2400):
    """:func:`render` and :func:`screenshot` from one start of headless Chromium (each start
    is 6-10 s on a loaded 2-core machine): the DOM after the scripts ran, laid out at
    ``width`` x ``height``, and the PNG's pixels."""
    import matplotlib.image

    out = _shot(path, out_png, width, height, dom=True)
    return out.stdout, matplotlib.image.imread(out_png)


def assert_nonblank(pixels, min_colours: int = 50) -> None:
    """The image shows something: many distinct colours, not one flat page."""
    rgb = (pixels[..., :3] * 255).astype(int)
    # the distinct colours at 5 bits per channel, each packed into one integer: the count of
    # np.unique(rows, axis=0), without its sort of 3-column rows (12 s on a 1200 x 2400 page)
    q = rgb.reshape(-1, 3) // 8
    colours = np.flatnonzero(np.bincount(q[:, 0] * 1024 + q[:, 1] * 32 + q[:, 2]))
    assert len(colours) >= min_colours, f"a near-blank image: {len(colours)} colours"
    assert (rgb.std(axis=(0, 1)) > 5).all()


#: a tick label with float noise (0.7999999999999999, 1.2999999999999998)
FLOAT_NOISE = re.compile(r"\d\.\d*(?:9{6,}|0{6,})\d")


def tick_labels(dom: str, axis: str) -> list[list[str]]:
    """The tick labels plotly drew, per axis element (``axis`` ``x`` or ``y``)."""
    groups = re.findall(rf'<g class="{axis}tick">(.*?)</g>', dom, re.S)
    labels = [re.sub(r"<[^>]+>", "", g).strip() for g in groups]
    # one list per drawn axis: plotly puts each axis' ticks in its own <g class="xaxislayer-above">
    layers = re.findall(rf'<g class="{axis}axislayer-above">(.*?)</g></g>', dom, re.S)
    per_axis = [
        [re.sub(r"<[^>]+>", "", x).strip() for x in re.findall(r"<text[^>]*>(.*?)</text>", layer)]
        for layer in layers
    ]
    return per_axis or [labels]


def assert_rendered(dom: str, divs: list[str]) -> None:
    """Every plot div holds plotly's SVG, the page says ``rendered``, no script error."""
    errors = re.search(r'<pre id="report-errors"[^>]*>(.*?)</pre>', dom, re.S)
    assert errors is not None
    assert errors.group(1).strip() == "", errors.group(1)
    assert 'data-status="rendered"' in dom, dom[:500]
    starts = sorted(dom.index(f'id="{div}"') for div in divs)
    for div in divs:
        start = dom.index(f'id="{div}"')
        later = [s for s in starts if s > start] + [dom.index('id="report-errors"')]
        chunk = dom[start : later[0]]
        assert "main-svg" in chunk and "<path" in chunk, f"{div}: no rendered SVG"
