"""The defaults that depend on the scenario as a whole, as one scenario resolves them: what
``imdrive show PRESET --all`` prints beside an unset setting (``Scenario.to_toml``) and
``summary.json`` lists as ``"resolved"``. They come from the one resolver,
:mod:`imdrive.config.defaults`.
"""

from __future__ import annotations


def resolved_defaults(sc) -> dict[str, object]:
    """Dotted key -> the value a scenario-dependent setting takes in ``sc``.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    dict
        Every setting of :data:`imdrive.config.defaults.DERIVED` that acts in ``sc``
        (:func:`~imdrive.config.defaults.derived_defaults`): the controller's choices and
        bandwidths, the limits and sensor ranges, the MRAS's acceleration tracking with the
        MRAS in the loop, the compensator's machine-dependent settings with it on and the
        injection's frequency with the injection on; only the plant's for an open-loop drive.
    """
    from imdrive.config.defaults import derived_defaults

    return derived_defaults(sc)


def unset_resolved_defaults(sc) -> dict[str, object]:
    """:func:`resolved_defaults` of the settings ``sc`` leaves unset (``None``): what
    ``summary.json`` lists as ``"resolved"``."""
    out = {}
    for key, value in resolved_defaults(sc).items():
        obj = sc
        for part in key.split("."):  # "plant.thermal.Rth1_K_per_W": three levels
            obj = getattr(obj, part)
        if obj is None:
            out[key] = value
    return out
