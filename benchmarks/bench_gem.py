"""Free acceleration in gym-electric-motor (GEM), for a speed and sanity comparison with imdrive.

Run with the peers venv (see benchmarks/README.md), NOT the imdrive venv::

    benchmarks/.venv-peers/bin/python benchmarks/bench_gem.py [--repeat N] [--json PATH]
        [--imdrive-csv PATH] [--solvers euler,solve_ivp,solve_ivp_tight]

The same experiment as bench_motulator.py: the paper's Table IV machine (R1 = 0.435 ohm,
R2 = 0.816 ohm, Ll1 = Ll2 = 2 mH, M = 69.3 mH, 2 pole pairs, J = 0.069 kg m^2) from standstill on a
balanced 220 V, 60 Hz supply, 1.5 s, no load, control period 100 us.

How it is built with GEM's public API (GEM is a reinforcement-learning environment; it has no
open-loop supply, so the "agent" below is the supply):

* ``gem.make("Cont-CC-SCIM-v0", ...)``: squirrel-cage induction motor, continuous (dynamically
  averaged) B6 bridge, ideal DC supply, control period ``tau = 1e-4`` s. GEM's SCIM model is
  the T-equivalent circuit with states (i_s, psi_r) in the stator frame, so the parameters map
  one to one (``r_s = R1, r_r = R2, l_m = M, l_sigs = Ll1, l_sigr = Ll2, p = 2``).
* Mechanics: ``PolynomialStaticLoad(a = b = c = 0)``, i.e. no load torque; the inertia is split
  ``j_rotor = j_load = J/2`` (GEM divides by ``j_load`` before it adds the rotor's).
* Supply: at every step k the agent's action is the duty-cycle triple ``u_abc / (u_dc/2)`` of the
  sinusoid sampled at mid-period ``t_k + Ts/2`` (u_dc = 400 V, so nothing clips; no
  interlocking time), which GEM holds over ``[t_k, t_k + Ts)`` -- exactly the voltage sequence
  imdrive applies.
* The current-control environment's own pieces are left in place but made inert: the episode
  constraints are removed (``constraints=()``), the limits raised (500 A, 400 rad/s) so the
  105 A starting current does not end the episode; its random current reference and its reward
  are still computed every step (part of GEM's step cost, a few per cent).
* Solvers: ``euler`` (GEM's ``EulerSolver``: one explicit Euler step per period),
  ``solve_ivp`` (scipy's solve_ivp, RK45, default rtol = 1e-3, atol = 1e-6, called once per
  period as motulator does) and ``solve_ivp_tight`` (the same at rtol = atol = 1e-8); on request
  ``scipy_ode`` (``ScipyOdeSolver()``: scipy.integrate.ode with ``dopri5`` at its default
  tolerances), which is GEM 3.0.3's default for ``Cont-CC-SCIM-v0`` (the environment passes
  ``ps.ScipyOdeSolver`` as the default of ``ode_solver``), not Euler.

Timing: wall time of the 15 000 ``env.step`` calls (median of ``--repeat``); ``reset`` and the
set-up are not timed.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import sys
import time

import numpy as np

try:
    import gym_electric_motor as gem
    from gym_electric_motor.physical_systems import PolynomialStaticLoad
    from gym_electric_motor.physical_systems.solvers import (
        EulerSolver,
        ScipyOdeSolver,
        ScipySolveIvpSolver,
    )
except ImportError as exc:  # pragma: no cover - run in the peers venv only
    sys.exit(
        f"gym-electric-motor is not importable ({exc}); run this with "
        "benchmarks/.venv-peers/bin/python (see benchmarks/README.md)"
    )

R1, R2, LL1, LL2, M, N_P, J = 0.435, 0.816, 2e-3, 2e-3, 69.3e-3, 2, 0.069
V_LL, F_HZ, T_END, TS = 220.0, 60.0, 1.5, 100e-6
U_DC = 400.0
SOLVERS = {
    "euler": lambda: EulerSolver(),
    "solve_ivp": lambda: ScipySolveIvpSolver(),
    "solve_ivp_tight": lambda: ScipySolveIvpSolver(rtol=1e-8, atol=1e-8),
    "scipy_ode": lambda: ScipyOdeSolver(),  # GEM 3.0.3's default for this environment
}


def make_env(solver: str):
    params = dict(r_s=R1, r_r=R2, l_m=M, l_sigs=LL1, l_sigr=LL2, p=N_P, j_rotor=J / 2)
    limits = dict(omega=400.0, torque=500.0, i=500.0, epsilon=math.pi, u=U_DC)
    return gem.make(
        "Cont-CC-SCIM-v0",
        motor=dict(motor_parameter=params, limit_values=limits, nominal_values=limits),
        load=PolynomialStaticLoad(load_parameter=dict(a=0.0, b=0.0, c=0.0, j_load=J / 2)),
        supply=dict(u_nominal=U_DC),
        ode_solver=SOLVERS[solver](),
        constraints=(),
        tau=TS,
        visualization=(),
    )


def run_once(solver: str):
    env = make_env(solver)
    env.reset(seed=0)
    ps = env.unwrapped.physical_system
    n = int(round(T_END / TS))
    v1 = math.sqrt(2.0 / 3.0) * V_LL
    w = 2.0 * math.pi * F_HZ
    s3 = 0.5 * math.sqrt(3.0)
    y = np.empty((n + 1, 6))  # [omega, i_alpha, i_beta, psi_r_alpha, psi_r_beta, epsilon]
    y[0] = ps._ode_solver.y
    t0 = time.perf_counter()
    for k in range(n):
        th = w * (k + 0.5) * TS
        ua, ub = v1 * math.cos(th), v1 * math.sin(th)
        action = np.array([ua, -0.5 * ua + s3 * ub, -0.5 * ua - s3 * ub]) / (0.5 * U_DC)
        _, _, terminated, _, _ = env.step(action)
        y[k + 1] = ps._ode_solver.y
        if terminated:
            raise RuntimeError(f"GEM ended the episode at step {k}")
    wall = time.perf_counter() - t0
    env.close()
    return y, wall


def figures(y) -> dict[str, float]:
    t = np.arange(len(y)) * TS
    rpm = y[:, 0] * 30 / math.pi
    i_a, i_b, p_a, p_b = y[:, 1], y[:, 2], y[:, 3], y[:, 4]
    tau = 1.5 * N_P * M / (LL2 + M) * (p_a * i_b - p_b * i_a)
    k = int(np.argmax(rpm >= 1700.0))
    t1700 = float(np.interp(1700.0, rpm[k - 1 : k + 1], t[k - 1 : k + 1]))
    return {
        "peak_torque_Nm": float(tau.max()),
        "peak_current_A": float(np.hypot(i_a, i_b).max()),
        "time_to_1700_rpm_s": t1700,
        "final_speed_rpm": float(rpm[-1]),
    }


def compare_with_imdrive(y, csv_path: str) -> dict[str, float]:
    """Max stator-current and speed differences at the common sampling instants."""
    data = np.genfromtxt(csv_path, delimiter=",", names=True)
    n = min(len(y), len(data))
    di = np.hypot(y[:n, 1] - data["i_alpha_A"][:n], y[:n, 2] - data["i_beta_A"][:n])
    dn = np.abs(y[:n, 0] * 30 / math.pi - data["speed_rpm"][:n])
    return {"max_current_diff_A": float(di.max()), "max_speed_diff_rpm": float(dn.max())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per solver (median reported)")
    ap.add_argument(
        "--solvers",
        default="euler,solve_ivp,solve_ivp_tight",
        help="comma-separated, of: " + ",".join(SOLVERS),
    )
    ap.add_argument("--json", metavar="PATH", help="write the figures as JSON")
    ap.add_argument("--imdrive-csv", metavar="PATH", help="imdrive's free-acceleration CSV")
    args = ap.parse_args(argv)
    from importlib.metadata import version

    out = {
        "gym_electric_motor": version("gym_electric_motor"),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "simulated_s": T_END,
        "Ts_s": TS,
        "runs": {},
    }
    print(f"gym-electric-motor {out['gym_electric_motor']} on Python {out['python']}")
    for solver in args.solvers.split(","):
        walls = []
        y = None
        for _ in range(args.repeat):
            y, wall = run_once(solver)
            walls.append(wall)
        wall = statistics.median(walls)
        entry = {"wall_s": wall, "walls_s": walls, "real_time_factor": T_END / wall, **figures(y)}
        if args.imdrive_csv:
            entry.update(compare_with_imdrive(y, args.imdrive_csv))
        out["runs"][solver] = entry
        print(f"\n{solver}: median of {args.repeat}")
        for k, v in entry.items():
            if k != "walls_s":
                print(f"  {k:<22} {v:.6g}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
