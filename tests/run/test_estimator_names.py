"""Names of the estimators come from their registration, not from hand-kept lists."""

from __future__ import annotations

from imdrive.config.control import ControlSettings
from imdrive.config.registry import ESTIMATOR_SETTINGS
from imdrive.run.plots import ESTIMATOR_NAMES, estimator_legend, signal_label


def test_every_package_estimator_has_a_legend_of_its_own():
    package = {n: c for n, c in ESTIMATOR_SETTINGS.items() if c.estimator_section}
    assert {"mras", "reactive-mras", "smo-mras", "afo", "ekf"} <= set(package)
    for name, cls in package.items():
        assert estimator_legend(name) == cls.estimator_legend != name, name
    assert ESTIMATOR_NAMES["smo-mras"] == "sliding-mode MRAS"  # the list that had drifted
    assert estimator_legend("measured") == "measured"
    assert estimator_legend("nosuch") == "nosuch"


def test_the_speed_feedback_help_names_every_package_estimator():
    from imdrive.config.schema import setting_paths  # noqa: F401  (the schema is built)

    field = ControlSettings.__dataclass_fields__["speed_feedback"]
    text = " ".join(str(m) for m in getattr(field.type, "__metadata__", ())) + str(field)
    for name, cls in ESTIMATOR_SETTINGS.items():
        if cls.estimator_section:
            assert f'"{name}"' in text, name


def test_the_speed_estimate_legend_names_the_estimator():
    class Run:  # what signal_label reads of a result
        class scenario:  # noqa: N801
            class control:  # noqa: N801
                speed_feedback = "smo-mras"

    assert signal_label("speed_est_rpm", Run()).endswith("(sliding-mode MRAS)")
