"""A matplotlib figure that shows itself in a notebook.

The package builds its figures as :class:`matplotlib.figure.Figure` objects, not through
``pyplot``: no global state, safe in threads and in the batch's worker processes. IPython's
inline backend only displays figures it manages (pyplot's), or any ``Figure`` once pyplot has
been imported in the kernel; a figure returned by ``res.plot()`` in a fresh notebook would print
as ``<Figure size 800x780 with 3 Axes>``. :class:`DisplayFigure` adds the rich-display hook
IPython looks for (``_repr_png_``), so the last expression of a cell shows as an image whatever
the backend; where the inline backend has registered its own formatter for ``Figure``, that one
is used (IPython asks type-registered formatters first), so the image is never shown twice.
"""

from __future__ import annotations

import io
from pathlib import Path

from matplotlib.figure import Figure

#: resolution of the notebook image, dots per inch
DISPLAY_DPI = 100


class DisplayFigure(Figure):
    """A :class:`matplotlib.figure.Figure` with a PNG rich representation for notebooks."""

    def _repr_png_(self) -> bytes:
        """The figure as PNG bytes (IPython's rich display)."""
        buf = io.BytesIO()
        self.savefig(buf, format="png", dpi=DISPLAY_DPI, bbox_inches="tight")
        return buf.getvalue()


def new_figure(**kwargs) -> DisplayFigure:
    """A :class:`DisplayFigure` (``Figure``'s keyword arguments: ``figsize``, ``layout``...)."""
    return DisplayFigure(**kwargs)


def save_png(fig: Figure, path, dpi: int) -> Path:
    """Write ``fig`` as a PNG at ``path`` by the package's output rule for one file
    (:func:`imdrive._io.output_file`): the path checked first (a folder, a device node, a FIFO,
    a link to nothing or a missing folder is refused with a :class:`~imdrive.errors.ConfigError`
    naming it), a symbolic link written through, the file written under a temporary name and
    renamed, so a failed or killed writer leaves no half-written image. Returns ``path``."""
    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    path = Path(path)
    with output_file(path, refuse=lambda problem: ConfigError("out_dir", problem)) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    return path
