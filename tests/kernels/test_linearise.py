"""The Newton step of the stability map's fixed-point solver (kernels/linearise.py)."""

from __future__ import annotations

import numpy as np

from imdrive.kernels.linearise import N_Z, _newton_step


def test_newton_step_solves_as_lapack():
    """``(A - I) dz = r`` to rounding, against numpy's LAPACK solve, on Jacobians shaped like
    the map's (a contraction near the unit circle, so ``A - I`` is ill-conditioned)."""
    rng = np.random.default_rng(7)
    dz, M = np.empty(N_Z), np.empty((N_Z, N_Z))
    for scale in (0.5, 0.99, 0.9999):
        A = scale * np.linalg.qr(rng.standard_normal((N_Z, N_Z)))[0]
        A += 1e-3 * rng.standard_normal((N_Z, N_Z))
        r = rng.standard_normal(N_Z)
        assert _newton_step(A, r, dz, M)
        ref = np.linalg.solve(A - np.eye(N_Z), r)
        cond = np.linalg.cond(A - np.eye(N_Z))
        assert np.max(np.abs(dz - ref)) <= 1e-13 * cond * np.max(np.abs(ref))


def test_newton_step_reports_a_singular_matrix():
    A = np.eye(N_Z)  # A - I = 0
    assert not _newton_step(A, np.ones(N_Z), np.empty(N_Z), np.empty((N_Z, N_Z)))


def test_the_map_kernels_find_the_engine_themselves():
    """``propagate`` with the engine's address given or looked up: the same run."""
    from imdrive.config.scenario import Scenario
    from imdrive.kernels.linearise import map_engine, propagate
    from imdrive.stability.linear import map_scenario, operating_point

    op = operating_point(map_scenario(Scenario.read("sensorless")), 600.0, 6.0)
    d = op._ops.drive
    outs = []
    for engine in (None, map_engine(d.P, d.S)):
        S = type(d.S)(*(f.copy() for f in d.S))
        out = np.empty(N_Z)
        assert propagate(d.P, S, 0, op.z.copy(), 20, d.TH[0, 0], d.TH[0, 1], out, engine) == 0
        outs.append(out)
    assert outs[0].tobytes() == outs[1].tobytes()
