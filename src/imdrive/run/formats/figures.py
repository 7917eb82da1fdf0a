"""The PNG figures of a run (:func:`imdrive.run.plots.save_figures`)."""

from __future__ import annotations

from pathlib import Path

from imdrive.run.formats import OutputFormat


def _write(res, folder: Path) -> None:
    from imdrive.run.plots import save_figures

    save_figures(res, folder)


FORMAT = OutputFormat(
    name="figures",
    key="figures",
    files=("*.png",),
    write=_write,
    description="PNG figures: speed.png, torque.png, currents.png; estimator.png with vector "
    "control, compensation.png with the R2 compensator",
    order=40,
)
