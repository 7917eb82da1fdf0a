"""Steady state and small-signal model of the whole sensorless closed loop.

Method
------
*Steady state.* With constant references and the compensator frozen, every state of the drive
is constant in the controller's synchronous frame at the sample instants (the drive is
rotation-invariant; :mod:`imdrive.kernels.linearise`). The operating point is the fixed point
``z* = F(z*)`` of the one-period map ``F`` of the discrete closed loop seen in that frame (the
engine's own period: RK4 plant, estimator, IFOC, inverter), found by Newton's method on
``F(z) - z``
with a central-difference Jacobian. Newton needs a good start; it comes from the continuous
steady state of the loop with imposed currents, solved for the two unknowns ``iq*`` and the
true speed ``w_m`` (:func:`continuous_steady_state`):

* speed loop (integral action): speed feedback = reference, so in the controller's frame
  ``w_e = n_p w_fb + w_sl*``, ``w_sl* = (R2_hat/L2_hat) iq*/id*``, ``id* = psi*/M_hat``;
* current loops (integral action): ``i_s = id* + j iq*`` in that frame;
* plant: ``psi_r = M i_s / (1 + j (w_e - n_p w_m) T2)``, ``psi_s = L1 i_s + M i_r``,
  ``T_e = 1.5 n_p Im(psi_s* i_s) = T_L + (B + b) w_m + k_fan w_m |w_m|``;
* MRAS at rest (Schauder 1992, eqs. 8, 9 of the paper): ``e = Im(lam_hat* lam) = 0``. The
  adjustable model gives ``lam_hat = M_hat id*`` (real), so the reference model's flux
  ``(L2_hat/M_hat)[(v - R1_hat i_s)/(j w_e) - sigma_hat L1_hat i_s]`` must be real too; with
  ``v = R1 i_s + j w_e psi_s``::

      sigma_hat L1_hat iq* - Im(psi_s) + (R1 - R1_hat) id* / w_e = 0

  (the measured-speed drive replaces this by ``w_m = w_ref``). With exact R1 and inductances it
  says ``Im(psi_r) = 0``: correct orientation, and the R2 error goes into the speed, as in
  :func:`imdrive.analysis.foc.foc_operating_point` (which this generalises to R1_hat, M_hat,
  friction and fan loads; a test checks the two agree). The ``1/w_e`` term is the classic
  difficulty of voltage-model estimators near zero stator frequency (Ohtani, Takada, Tanaka,
  IEEE Trans. Ind. Appl. 28(1), 1992; Kubota, Matsuse, Nakano, IEEE Trans. Ind. Appl. 29(2),
  1993): with an R1 error there is no steady state at ``w_e = 0``. The adaptive observer's
  drive starts from the same point (with R̂ = R its own rest, no current error, is the same
  orientation), its states from its ``ReducedState.steady``; Newton then finds its own
  fixed point.

*Linearisation.* The Jacobians ``A = dF/dz``, ``B = dF/du`` at ``z*`` (``u`` = speed
reference, load torque) are the exact small-signal model of the discrete closed loop at the
control period Ts: the controller is discrete, so a discrete model represents its sampling and
one-period computation delay without a Padé or delay approximation; the continuous-time
eigenvalues reported are ``s = ln(lambda) / Ts``. Why discrete, measured: the linear model
matches the nonlinear loop's response to 1e-3 relative (tests/stability/test_stability.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.estimators import mras
from imdrive.run import linear as rl
from imdrive.run.linear import (  # noqa: F401  (re-exported: old names)
    StationaryDrive,
    model_coefficients,
    stationary_drive,
)
from imdrive.stability.steady import (  # noqa: F401  (re-exported: old path)
    _initial_state,
    _plant_in_frame,
    continuous_steady_state,
    second_integrator_runs,
)

_Drive = StationaryDrive  # the 0.2 private names, kept for callers that reached in
_stationary_drive = stationary_drive
_coefficients = model_coefficients

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm

#: names of the plant's and the controller's states in the reduced state (see
#: imdrive.kernels.linearise), synchronous frame, SI units; the estimator's follow
DRIVE_STATE_NAMES = (
    "psi_s_d", "psi_s_q", "psi_r_d", "psi_r_q", "w_m",
    "v_prev_d", "v_prev_q", "i_prev_d", "i_prev_q",
    "int_w", "int_d", "int_q", "psi_hat",
)  # fmt: skip
#: names of the MRAS drive's reduced state (any drive's: :attr:`OperatingPoints.state_names`)
STATE_NAMES = DRIVE_STATE_NAMES + mras.REDUCED_NAMES
INPUT_NAMES = ("speed_ref_rpm", "load_torque_Nm")
OUTPUT_NAMES = ("speed_rpm", "speed_est_rpm", "i_d_A", "i_q_A")

#: per-point status strings of :func:`solve_operating_points` and the maps
STATUS_OK = "ok"
STATUS_CURRENT = "current_limit"  # the load needs more than the controller's current limit
STATUS_VOLTAGE = "voltage_limit"  # the steady state needs more than the inverter's voltage
STATUS_NONE = "no_steady_state"  # no equilibrium (e.g. zero stator frequency with R1 error)
STATUS_DIVERGED = "diverged"  # the one-period map left the engine's bounds

_NEWTON_TOL = 1e-10
_NEWTON_ITER = 40
#: where Newton does not converge from the continuous guess, the drive runs this many rotor
#: time constants L2/R2 from it and Newton starts again there (:func:`_newton`)
_SETTLE_T2 = 25.0


# ------------------------------------------------------------------------------------------
# the drive, made stationary


def map_scenario(
    sc: Scenario,
    *,
    R1_ratio: float | None = None,
    R2_ratio: float | None = None,
    M_ratio: float | None = None,
) -> Scenario:
    """The scenario the maps analyse: compensator and injection off, estimates optionally scaled.

    ``R1_ratio`` sets the controller's ``R1_hat = R1_ratio * R1`` (plant R1 at the reference
    temperature times the final value of ``plant.R1_scale``); likewise ``R2_ratio`` and
    ``M_ratio`` (``M_hat``). Gains that default from the model (current PIs, MRAS K2) follow
    the estimates, as they would in a drive commissioned with them.

    Parameters
    ----------
    sc : Scenario
        The drive.
    R1_ratio, R2_ratio, M_ratio : float, optional
        ``R1_hat/R1``, ``R2_hat/R2``, ``M_hat/M``, dimensionless; None keeps the scenario's
        estimate.

    Returns
    -------
    Scenario
        The scenario with compensator and injection off and the estimates set.
    """
    est = sc.estimator
    m = sc.machine
    ch = {}
    for name, ratio, base in (
        ("R1_ohm", R1_ratio, m.R1_ohm * sc.plant.R1_scale.final),
        ("R2_ohm", R2_ratio, m.R2_ohm * sc.plant.R2_scale.final),
        ("M_H", M_ratio, m.M_H),
    ):
        if ratio is not None:
            if not (math.isfinite(ratio) and ratio > 0):
                raise ConfigError(f"{name[:2]}_ratio", f"must be finite and > 0 (got {ratio})")
            ch[name] = ratio * base
    comp = replace(sc.compensator, enabled=False)
    inj = replace(sc.injection, amplitude_A=None, amplitude_pu=None)
    return replace(sc, estimator=replace(est, **ch), compensator=comp, injection=inj)


# ------------------------------------------------------------------------------------------
# operating points


@dataclass
class OperatingPoints:
    """Fixed points and Jacobians of many (speed, torque) pairs of one drive.

    Attributes
    ----------
    speed_ref_rpm, torque_Nm : ndarray
        The requested points (speed reference, load torque).
    status : ndarray of str
        ``ok``, ``current_limit``, ``voltage_limit``, ``no_steady_state`` or ``diverged``.
    z : ndarray (N, n)
        Fixed points (:attr:`state_names`), NaN where no steady state.
    A : ndarray (N, n, n)
        ``dF/dz``: the discrete small-signal model, one period Ts.
    B : ndarray (N, n, 2)
        ``dF/du`` for ``u`` = (speed reference in mechanical rad/s, load torque in N m).
    residual : ndarray
        Scaled fixed-point residual.
    iterations : ndarray
        Newton iterations on the discrete map.
    Ts : float
        Control period, s.
    drive : StationaryDrive
        The records (row ``i`` is point ``i``), for :func:`propagate`.
    state_names : tuple of str
        The reduced state's names: :data:`DRIVE_STATE_NAMES`, then the estimator's
        (``ReducedState.names``; the MRAS drive's: :data:`STATE_NAMES`).
    speed_state : str
        The name of the speed estimate among them.
    """

    speed_ref_rpm: np.ndarray
    torque_Nm: np.ndarray
    status: np.ndarray
    z: np.ndarray
    A: np.ndarray
    B: np.ndarray
    residual: np.ndarray
    iterations: np.ndarray
    Ts: float
    drive: StationaryDrive = field(repr=False)
    coeffs: dict = field(repr=False, default_factory=dict)
    state_names: tuple[str, ...] = STATE_NAMES
    speed_state: str = "w_r_hat"

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of every ``A`` (N, n), z-plane; NaN rows where status is not ok."""
        ev = np.full(self.A.shape[:2], np.nan + 0j)
        ok = self.status == STATUS_OK
        if ok.any():
            ev[ok] = np.linalg.eigvals(self.A[ok])
        return ev


def solve_operating_points(
    sc: Scenario, speeds_rpm, torques_Nm, flux_factor: float | None = None
) -> OperatingPoints:
    """Steady states and linearisations of ``sc`` at paired ``speeds_rpm[i], torques_Nm[i]``.

    ``sc`` is analysed as given (call :func:`map_scenario` first to switch the compensator off,
    which the maps do). Points the drive cannot hold get a status, never an exception.
    ``flux_factor`` (a drive with ``control.field_weakening``): the field weakening's flux
    factor ``k`` at these points, held there (its integrator frozen: the loop is slow and not
    a state of the reduced map), so the flux reference is ``k psi*`` and the speed PI's gains
    are scaled as the drive scales them (:mod:`imdrive.kernels.speed_control`).
    """
    speeds = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    torques = np.atleast_1d(np.asarray(torques_Nm, dtype=float))
    if speeds.shape != torques.shape or speeds.ndim != 1 or speeds.size == 0:
        raise ConfigError("points", "speeds and torques must be 1-D, non-empty, of equal length")
    if not (np.all(np.isfinite(speeds)) and np.all(np.isfinite(torques))):
        raise ConfigError("points", "speeds and torques must be finite")
    if sc.compensator.enabled or sc.injection.amplitude_A or sc.injection.amplitude_pu:
        sc = map_scenario(sc)
    n = len(speeds)
    w_ref = speeds * RPM
    d = stationary_drive(sc, w_ref, torques)
    c = model_coefficients(d.P, d.S)
    if flux_factor is not None:
        d.S.control["fw_cut"][:] = 1.0 - flux_factor
        d.P.control["fw_rate"][:] = 0.0
        c["psi_ref"] *= flux_factor
    iq, w_m, ok = continuous_steady_state(c, w_ref, torques)
    status = np.full(n, STATUS_OK, dtype=object)
    status[~ok] = STATUS_NONE
    i_d = c["psi_ref"] / c["M_hat"]
    with np.errstate(all="ignore"):
        I_mag = np.hypot(i_d, iq)
        I, psi_s, _, w_e, _ = _plant_in_frame(c, iq, w_m, w_ref)
        V_mag = np.abs(c["R1"] * I + 1j * w_e * psi_s)
    status[ok & (I_mag > d.i_max)] = STATUS_CURRENT
    status[ok & (I_mag <= d.i_max) & (V_mag > d.v_max)] = STATUS_VOLTAGE
    red = rl.reduced_state_of(d.S)
    n_z = rl.N_D + len(red.names)
    Z = np.zeros((n, n_z))
    good = status == STATUS_OK
    if good.any():
        Z[good] = _initial_state(c, d.Ts, iq[good], w_m[good], w_ref[good], d.P, d.S)
    A = np.full((n, n_z, n_z), np.nan)
    B = np.full((n, n_z, rl.N_U), np.nan)
    res = np.full(n, np.nan)
    its = np.zeros(n, dtype=np.int64)
    idx = np.flatnonzero(good)
    if len(idx):
        # the hidden states the reduced map does not carry, at the operating point's values, in
        # the drive itself (its propagate() runs from them too)
        if "w_flux" in d.S.est.dtype.names:
            # the flux frequency the MRAS filter's cut-off follows (mras.wc_per_stator_frequency)
            # at the operating point's, and held there (an infinite time constant): a low-pass
            # over 0.5 s whose own slow mode is not in the reduced state
            d.S.est["w_flux"][idx] = w_e[idx]
            d.P.est["wc_tau"][idx] = np.inf
        if "int_w_run" in d.S.est.dtype.names:
            # the type-2 MRAS's second integrator runs at the operating point's stator
            # frequency, read from the controller's (not a state of the reduced map)
            d.S.est["int_w_run"][idx] = second_integrator_runs(c, w_e[idx])
        # the controller's last stator frequency, which the estimator reads (the MRAS's
        # second integrator, the observer's adaptation share and its direct orientation):
        # the operating point's
        d.S.control["w_e"][idx] = w_e[idx]
        settle = int(round(_SETTLE_T2 * c["L2"] / c["R2"] / d.Ts))
        Zs, As, Bs, sts, rs, its_s = _newton(d, idx, Z[idx], settle)
        Z[idx], A[idx], B[idx], res[idx], its[idx] = Zs, As, Bs, rs, its_s
        status[idx[sts == rl.P_NO_CONVERGENCE]] = STATUS_NONE
        status[idx[sts == rl.P_DIVERGED]] = STATUS_DIVERGED
    bad = status != STATUS_OK
    Z[bad] = np.nan
    A[bad] = np.nan
    B[bad] = np.nan
    # a fixed point on a limit is not the requested operating point
    with np.errstate(invalid="ignore"):
        v_fix = np.hypot(Z[:, 5], Z[:, 6])
        iq_max = math.sqrt(max(d.i_max**2 - i_d**2, 0.0))
        status[(status == STATUS_OK) & (v_fix >= d.v_max * (1 - 1e-9))] = STATUS_VOLTAGE
        status[(status == STATUS_OK) & (np.abs(Z[:, 9]) >= iq_max * (1 - 1e-9))] = STATUS_CURRENT
    return OperatingPoints(
        speed_ref_rpm=speeds,
        torque_Nm=torques,
        status=status,
        z=Z,
        A=A,
        B=B,
        residual=res,
        iterations=its,
        Ts=d.Ts,
        drive=d,
        coeffs=c,
        state_names=DRIVE_STATE_NAMES + tuple(red.names),
        speed_state=red.speed,
    )


def _rows(d: StationaryDrive, idx):
    """The records of rows ``idx`` of ``d`` (a copy of the state; parameters sliced)."""
    n = d.TH.shape[0]
    P = rl.DriveParams(*(f[idx] if f.ndim >= 1 and f.shape[0] == n else f for f in d.P))
    S = rl.DriveState(*(f[idx].copy() for f in d.S))
    return P, S, np.ascontiguousarray(d.TH[idx])


def _newton(d: StationaryDrive, idx, Z0, settle: int):
    """Newton's method on the discrete map at rows ``idx`` of ``d`` from the guesses ``Z0``;
    where it does not converge, again from the state the drive itself reaches in ``settle``
    periods from the guess (:func:`imdrive.kernels.linearise.propagate`).

    The continuous guess is the MRAS's rest (module docstring); an estimator whose rest
    differs, with an estimate off, can start Newton outside its basin: on the default map of
    ``injection-robust`` (the adaptive observer, R̂1 = 1.1 R1, R̂2 = 1.2 R2) 46 of its 65
    points without a steady state had one (44 stable; where checked, the drive run 4 s from
    the guess settled to 1e-11 per second), and 19 of 26 on the same drive with the MRAS.
    Returns ``(Z, A, B, status, residual, iterations)`` of the rows.
    """
    P, S, TH = _rows(d, idx)
    n, n_z = Z0.shape
    Z = np.ascontiguousarray(Z0.copy())
    A = np.empty((n, n_z, n_z))
    B = np.empty((n, n_z, rl.N_U))
    st = np.empty(n, dtype=np.int64)
    res = np.empty(n)
    its = np.empty(n, dtype=np.int64)
    rl.solve_points(P, S, Z, TH, A, B, st, res, its, _NEWTON_TOL, _NEWTON_ITER)
    again = np.flatnonzero(st == rl.P_NO_CONVERGENCE)
    if len(again) and settle > 0:
        P2, S2, TH2 = _rows(d, idx[again])
        Z2 = np.empty((len(again), n_z))
        ok = np.ones(len(again), dtype=bool)
        for k in range(len(again)):
            out = np.empty(n_z)
            z0 = np.ascontiguousarray(Z0[again[k]])
            ok[k] = rl.propagate(P2, S2, k, z0, settle, TH2[k, 0], TH2[k, 1], out) == 0
            Z2[k] = out
        A2, B2 = np.empty((len(again), n_z, n_z)), np.empty((len(again), n_z, rl.N_U))
        st2, res2 = np.empty(len(again), dtype=np.int64), np.empty(len(again))
        its2 = np.empty(len(again), dtype=np.int64)
        rl.solve_points(P2, S2, Z2, TH2, A2, B2, st2, res2, its2, _NEWTON_TOL, _NEWTON_ITER)
        use = ok & (st2 == rl.P_OK)
        rows = again[use]
        Z[rows], A[rows], B[rows], res[rows] = Z2[use], A2[use], B2[use], res2[use]
        st[rows] = rl.P_OK
        its[rows] = its2[use]
    return Z, A, B, st, res, its


# ------------------------------------------------------------------------------------------
# one operating point, for users


def output_matrix(c: dict, names=STATE_NAMES, speed: str = "w_r_hat") -> np.ndarray:
    """``C`` (4, n): speed (rpm), speed estimate (rpm), i_d, i_q (A) from the reduced state
    ``names`` (the MRAS drive's by default), whose speed estimate is ``speed``.

    The currents are the plant's stator current at the sample, in the controller's frame:
    ``i_s = (L2 psi_s - M psi_r) / (L1 L2 - M^2)``.
    """
    C = np.zeros((4, len(names)))
    C[0, 4] = 1.0 / RPM
    C[1, list(names).index(speed)] = 1.0 / (c["n_p"] * RPM)
    D = c["L1"] * c["L2"] - c["M"] ** 2
    for r, (s, p) in enumerate(((0, 2), (1, 3))):
        C[2 + r, s] = c["L2"] / D
        C[2 + r, p] = -c["M"] / D
    return C


@dataclass
class Mode:
    """One eigenvalue of the discrete loop and its continuous equivalent ``s = ln(z)/Ts``."""

    z: complex
    s: complex
    damping: float  # -Re(s)/|s|
    frequency_Hz: float  # |Im(s)| / 2 pi


def modes_from_eigenvalues(ev: np.ndarray, Ts: float) -> list[Mode]:
    """Modes sorted from the least stable (largest ``Re s``); zero eigenvalues are skipped."""
    out = []
    for lam in ev:
        if abs(lam) < 1e-12:
            continue
        s = np.log(lam) / Ts
        zeta = -s.real / abs(s) if abs(s) > 0 else 1.0
        out.append(Mode(complex(lam), complex(s), float(zeta), abs(s.imag) / (2 * math.pi)))
    out.sort(key=lambda m: -m.s.real)
    return out


@dataclass
class OperatingPoint:
    """The steady state of one (speed, load) point and its small-signal model.

    Attributes
    ----------
    speed_ref_rpm, torque_Nm : float
        Speed reference and load torque of the point.
    status : str
        ``ok`` or why there is no usable steady state (see :data:`STATUS_OK` ...).
    z : ndarray
        Fixed point of the rotated one-period map, :attr:`state_names` (SI units: Wb, rad/s,
        A, V).
    A, B, C : ndarray
        ``z[k+1] = z* + A dz[k] + B du[k]``, ``dy = C dz``; ``u`` in rpm and N m (B is scaled
        from rad/s), ``y`` = :data:`OUTPUT_NAMES`.
    Ts : float
        Sampling period of the discrete model, s.
    """

    speed_ref_rpm: float
    torque_Nm: float
    status: str
    z: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Ts: float
    _ops: OperatingPoints = field(repr=False, default=None)

    @property
    def speed_rpm(self) -> float:
        """True speed at the operating point, rpm."""
        return float(self.z[4] / RPM)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the reduced state (:attr:`OperatingPoints.state_names`)."""
        return self._ops.state_names

    @property
    def speed_est_rpm(self) -> float:
        """The estimator's speed estimate at the operating point, rpm."""
        k = self.state_names.index(self._ops.speed_state)
        return float(self.z[k] / (self._ops.coeffs["n_p"] * RPM))

    @property
    def current_dq_A(self) -> complex:
        """Stator current at the sample, controller's frame, A."""
        y = self.C @ self.z
        return complex(y[2], y[3])

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``A``.

        Returns
        -------
        ndarray
            Complex eigenvalues in the z-plane, dimensionless (stable inside the unit circle).
        """
        return np.linalg.eigvals(self.A)

    def modes(self) -> list[Mode]:
        """Modes from the least stable; see :func:`modes_from_eigenvalues`.

        Returns
        -------
        list of Mode
            Eigenvalue, s-plane equivalent (1/s), damping ratio and frequency (Hz) of each.
        """
        return modes_from_eigenvalues(self.eigenvalues(), self.Ts)

    @property
    def stable(self) -> bool:
        """All eigenvalues strictly inside the unit circle."""
        return bool(np.max(np.abs(self.eigenvalues())) < 1.0)

    def to_statespace(self):
        """The small-signal model as a discrete-time state-space system at ``Ts``.

        Inputs :data:`INPUT_NAMES` (speed reference in rpm, load torque in N m), outputs
        :data:`OUTPUT_NAMES`, states :attr:`state_names` (deviations from the operating point).
        A python-control ``StateSpace`` (named signals, ``control.bode_plot``,
        ``control.step_response``) when python-control is installed (``pip install
        imdrive[control]``), else a ``scipy.signal.StateSpace`` with the names in its attributes
        ``input_names``, ``output_names``, ``state_names``.

        Returns
        -------
        control.StateSpace or scipy.signal.StateSpace
            The discrete-time system ``(A, B, C, 0)`` with sampling period ``Ts``.
        """
        D = np.zeros((len(OUTPUT_NAMES), len(INPUT_NAMES)))
        try:
            import control
        except ImportError:
            from scipy.signal import StateSpace

            sys = StateSpace(self.A, self.B, self.C, D, dt=self.Ts)
            sys.input_names = list(INPUT_NAMES)
            sys.output_names = list(OUTPUT_NAMES)
            sys.state_names = list(self.state_names)
            return sys
        return control.ss(
            self.A,
            self.B,
            self.C,
            D,
            self.Ts,
            inputs=list(INPUT_NAMES),
            outputs=list(OUTPUT_NAMES),
            states=list(self.state_names),
            name=f"imdrive {self.speed_ref_rpm:g} rpm {self.torque_Nm:g} Nm",
        )

    def propagate(self, dz, n_steps: int, du=(0.0, 0.0)) -> np.ndarray:
        """The nonlinear loop's state deviation after ``n_steps`` periods from ``z* + dz``.

        Runs the engine itself (:func:`imdrive.kernels.linearise.propagate`); for checking
        the linear model.

        Parameters
        ----------
        dz : array_like
            Initial deviation from ``z``, :attr:`state_names` (SI units: Wb, rad/s, A, V).
        n_steps : int
            Control periods to run.
        du : tuple of float
            Speed reference step in rpm and load step in N m, held.

        Returns
        -------
        ndarray
            The state deviation after ``n_steps`` periods, SI units as ``dz`` (NaN if the
            loop diverged).
        """
        d = self._ops.drive
        P = d.P
        saved = P.prof_v[0, [rl.PR_SPEED_REF, rl.PR_LOAD], 0].copy()
        P.prof_v[0, rl.PR_SPEED_REF, 0] += du[0] * RPM
        P.prof_v[0, rl.PR_LOAD, 0] += du[1]
        try:
            S = rl.DriveState(*(f.copy() for f in d.S))
            out = np.empty(len(self.z))
            z0 = np.ascontiguousarray(self.z + np.asarray(dz, dtype=float))
            st = rl.propagate(P, S, 0, z0, int(n_steps), d.TH[0, 0], d.TH[0, 1], out)
        finally:
            P.prof_v[0, [rl.PR_SPEED_REF, rl.PR_LOAD], 0] = saved
        if st != 0:
            return np.full(len(self.z), np.nan)
        return out - self.z


def operating_point(sc: Scenario, speed_rpm: float, torque_Nm: float) -> OperatingPoint:
    """Steady state and discrete small-signal model of ``sc`` at one (speed, load) point.

    The compensator and injection are switched off (R2_hat frozen at the scenario's initial
    estimate). Estimation errors come from ``[estimator]`` (``R1_ohm``, ``R2_ohm``, ``M_H``) or
    :func:`map_scenario`. A point without steady state is returned with its ``status`` and NaNs.

    Parameters
    ----------
    sc : Scenario
        The sensorless drive.
    speed_rpm : float
        Speed reference, rpm.
    torque_Nm : float
        Load torque, N m.

    Returns
    -------
    OperatingPoint
        Fixed point, ``A``, ``B``, ``C`` and status.
    """
    ops = solve_operating_points(map_scenario(sc), [speed_rpm], [torque_Nm])
    C = output_matrix(ops.coeffs, ops.state_names, ops.speed_state)
    B = ops.B[0].copy()
    B[:, 0] *= RPM  # per rpm of speed reference
    return OperatingPoint(
        speed_ref_rpm=float(speed_rpm),
        torque_Nm=float(torque_Nm),
        status=str(ops.status[0]),
        z=ops.z[0],
        A=ops.A[0],
        B=B,
        C=C,
        Ts=ops.Ts,
        _ops=ops,
    )
