"""Free acceleration in motulator, for a speed and sanity comparison with imdrive.

Run with the peers venv (see benchmarks/README.md), NOT the imdrive venv::

    benchmarks/.venv-peers/bin/python benchmarks/bench_motulator.py [--repeat N] [--json PATH]
        [--imdrive-csv PATH] [--pwm [--dead-time T_D]]

It simulates the free acceleration of the paper's Table IV machine (R1 = 0.435 ohm,
R2 = 0.816 ohm, Ll1 = Ll2 = 2 mH, M = 69.3 mH, 2 pole pairs, J = 0.069 kg m^2) from standstill on
a 220 V, 60 Hz balanced supply, 1.5 s, no load, with motulator's induction-machine model, and
prints wall time, real-time factor, peak torque, the time to reach 1700 rpm and final values.

motulator models the machine in its Gamma form (magnetising inductance on the stator side). The
T-equivalent parameters convert exactly (no saturation) with ``k = L1/M``, ``L1 = Ll1 + M``,
``L2 = Ll2 + M``::

    L_s   = L1                              = 71.3 mH
    L_ell = L1 (L1 L2 - M^2) / M^2          = k^2 L2 - L1 = 4.1749 mH
    R_r   = k^2 R2                          = 0.86379 ohm
    R_s   = R1                              = 0.435 ohm

(rotor quantities referred by ``psi_r' = k psi_r``, ``i_r' = i_r / k``; stator quantities, torque
and speed are unchanged).

The supply is a minimal open-loop control system written with motulator's public API: at every
sampling instant t_k it samples the 220 V, 60 Hz sinusoid at mid-period, ``u = V1
exp(j w (t_k + Ts/2))``, and returns the duty ratios that make the converter apply ``u`` over
``[t_k, t_k + Ts)`` (a ZOH, ``pwm=False``, without computational delay, ``delay=0``): the same
voltage sequence imdrive applies. The DC bus is 400 V so that the sinusoidal duty ratios stay in
[0, 1]; the machine sees exactly ``u``. motulator integrates each period with scipy's solve_ivp
(RK45 by default, rtol = 1e-3, atol = 1e-6); ``--tight`` also runs rtol = atol = 1e-8.

``--pwm`` switches on motulator's carrier-comparison PWM (``Drive(pwm=True)``: the converter's
switching instants within each period, every interval between them integrated on its own),
``--dead-time T_D`` its converter dead time (``VoltageSourceConverter(t_d=T_D)``): the peers of
imdrive's switching bridge (``inverter.model = "switching"``, ``inverter.dead_time_s``).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

try:
    import motulator
    from motulator.common.control import ControlSystem
    from motulator.common.model import SolverCfg
    from motulator.drive.model import (
        Drive,
        InductionMachine,
        InductionMachinePars,
        MechanicalSystem,
        Simulation,
        VoltageSourceConverter,
    )
except ImportError as exc:  # pragma: no cover - run in the peers venv only
    sys.exit(
        f"motulator is not importable ({exc}); run this with benchmarks/.venv-peers/bin/python "
        "(see benchmarks/README.md)"
    )

# Table IV machine, T-equivalent circuit
R1, R2, LL1, LL2, M, N_P, J = 0.435, 0.816, 2e-3, 2e-3, 69.3e-3, 2, 0.069
V_LL, F_HZ, T_END, TS = 220.0, 60.0, 1.5, 100e-6
U_DC = 400.0


def gamma_parameters() -> dict[str, float]:
    """Gamma-model parameters of the T-equivalent machine (exact, see the module docstring)."""
    L1, L2 = LL1 + M, LL2 + M
    k = L1 / M
    return {"R_s": R1, "R_r": k**2 * R2, "L_ell": k**2 * L2 - L1, "L_s": L1}


@dataclass
class _Ref:
    T_s: float
    d_abc: np.ndarray
    u_s: complex


class OpenLoopSupply(ControlSystem):
    """Balanced sinusoidal voltage sampled at mid-period and held (no feedback)."""

    def __init__(self, v_peak: float, f_hz: float, T_s: float, u_dc: float) -> None:
        super().__init__()
        self.v_peak, self.w, self.T_s, self.u_dc = v_peak, 2 * math.pi * f_hz, T_s, u_dc
        self.k = 0  # period index: the phase is computed from it, not accumulated

    def get_measurement(self, mdl):
        return SimpleNamespace()

    def get_feedback(self, meas):
        return SimpleNamespace()

    def compute_output(self, fbk) -> _Ref:
        u = self.v_peak * complex(math.cos(th := self.w * (self.k + 0.5) * self.T_s), math.sin(th))
        # phase voltages of the space vector u, offset to mid-rail
        u_abc = np.array(
            [
                u.real,
                -0.5 * u.real + 0.5 * math.sqrt(3) * u.imag,
                -0.5 * u.real - 0.5 * math.sqrt(3) * u.imag,
            ]
        )
        return _Ref(T_s=self.T_s, d_abc=u_abc / self.u_dc + 0.5, u_s=u)

    def update(self, ref, fbk) -> None:
        super().update(ref, fbk)
        self.k += 1


def run_once(rtol: float | None = None, atol: float | None = None, pwm=False, t_d=0.0):
    """One free acceleration; ``pwm``: motulator's carrier comparison (the converter switches,
    each switching interval integrated on its own) instead of the period-average voltage;
    ``t_d``: its dead time, s."""
    par = InductionMachinePars(n_p=N_P, **gamma_parameters())
    mdl = Drive(
        machine=InductionMachine(par),
        mechanics=MechanicalSystem(J=J),
        converter=VoltageSourceConverter(u_dc=U_DC, t_d=t_d),
        pwm=pwm,
        delay=0,
    )
    ctrl = OpenLoopSupply(math.sqrt(2 / 3) * V_LL, F_HZ, TS, U_DC)
    cfg = SolverCfg() if rtol is None else SolverCfg(rtol=rtol, atol=atol)
    sim = Simulation(mdl, ctrl, show_progress=False, cfg=cfg)
    t0 = time.perf_counter()
    res = sim.simulate(t_stop=T_END)
    wall = time.perf_counter() - t0
    return res, wall, cfg


def figures(res) -> dict[str, float]:
    t = np.asarray(res.mdl.t)
    w_M = np.real(np.asarray(res.mdl.mechanics.w_M))
    tau = np.real(np.asarray(res.mdl.machine.tau_M))
    i_s = np.asarray(res.mdl.machine.i_s_ab)
    rpm = w_M * 30 / math.pi
    k1700 = int(np.argmax(rpm >= 1700.0))
    # linear interpolation between the solver points around the crossing
    t1700 = float(np.interp(1700.0, rpm[k1700 - 1 : k1700 + 1], t[k1700 - 1 : k1700 + 1]))
    sel = t <= T_END
    return {
        "peak_torque_Nm": float(tau[sel].max()),
        "peak_current_A": float(np.abs(i_s[sel]).max()),
        "time_to_1700_rpm_s": t1700,
        "final_speed_rpm": float(np.interp(T_END, t, rpm)),
        "solver_points": int(t.size),
    }


def compare_with_imdrive(res, csv_path: str) -> dict[str, float]:
    """Max stator-current and speed differences at imdrive's sampling instants."""
    data = np.genfromtxt(csv_path, delimiter=",", names=True)
    t = np.asarray(res.mdl.t)
    i_s = np.asarray(res.mdl.machine.i_s_ab)
    rpm = np.real(np.asarray(res.mdl.mechanics.w_M)) * 30 / math.pi
    # the solution is continuous; duplicate points at period boundaries are fine for interp
    order = np.argsort(t, kind="stable")
    t, i_s, rpm = t[order], i_s[order], rpm[order]
    tt = data["time_s"]
    ia = np.interp(tt, t, i_s.real)
    ib = np.interp(tt, t, i_s.imag)
    n = np.interp(tt, t, rpm)
    # only the sampling instants are exact points of both solutions
    return {
        "max_current_diff_A": float(
            np.max(np.hypot(ia - data["i_alpha_A"], ib - data["i_beta_A"]))
        ),
        "max_speed_diff_rpm": float(np.max(np.abs(n - data["speed_rpm"]))),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per setting (median reported)")
    ap.add_argument("--tight", action="store_true", help="also run with rtol = atol = 1e-8")
    ap.add_argument("--json", metavar="PATH", help="write the figures as JSON")
    ap.add_argument("--pwm", action="store_true", help="motulator's carrier-comparison PWM")
    ap.add_argument("--dead-time", type=float, default=0.0, help="converter dead time, s")
    ap.add_argument(
        "--imdrive-csv",
        metavar="PATH",
        help="timeseries.csv of 'imdrive run free-acceleration' to compare currents with",
    )
    args = ap.parse_args(argv)

    settings = [("default (RK45, rtol 1e-3, atol 1e-6)", None, None)]
    mode = ("pwm" if args.pwm else "average") + (
        f", dead time {args.dead_time:g} s" * bool(args.dead_time)
    )
    if args.tight:
        settings.append(("tight (RK45, rtol 1e-8, atol 1e-8)", 1e-8, 1e-8))
    gp = gamma_parameters()
    out = {
        "motulator": motulator.__version__ if hasattr(motulator, "__version__") else _version(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "gamma_parameters": gp,
        "simulated_s": T_END,
        "converter": mode,
        "Ts_s": TS,
        "runs": {},
    }
    print(f"motulator {out['motulator']} on Python {out['python']}")
    print("Gamma parameters: " + ", ".join(f"{k} = {v:.6g}" for k, v in gp.items()))
    for label, rtol, atol in settings:
        walls = []
        res = None
        for _ in range(args.repeat):
            res, wall, _ = run_once(rtol, atol, args.pwm, args.dead_time)
            walls.append(wall)
        wall = statistics.median(walls)
        fig = figures(res)
        entry = {"wall_s": wall, "walls_s": walls, "real_time_factor": T_END / wall, **fig}
        if args.imdrive_csv:
            entry.update(compare_with_imdrive(res, args.imdrive_csv))
        out["runs"][label] = entry
        print(f"\n{label}, converter {mode}: median of {args.repeat}")
        for k, v in entry.items():
            if k != "walls_s":
                print(f"  {k:<22} {v:.6g}" if isinstance(v, float) else f"  {k:<22} {v}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


def _version() -> str:
    from importlib.metadata import version

    return version("motulator")


if __name__ == "__main__":
    raise SystemExit(main())
