"""The drive's sequence: the speed reference and the load the kernels follow, resolved from
the scenario's profiles and the machine in one place (:func:`sequence`).

A scenario states its duty cycle as two profiles, each either absolute or in per-unit of the
machine (a pair of :data:`imdrive.config.pairs.PAIRS`):

* the speed reference, ``control.speed_ref_rpm`` or ``control.speed_ref_pu`` (per-unit of the
  machine's rated speed, :func:`imdrive.config.rated.rated_point`);
* the load torque, ``load.torque_Nm`` or ``load.torque_pu`` (per-unit of its rated torque).

Times are seconds either way. The field-oriented drive then sequences them as an industrial
drive does:

1. **Premagnetisation.** The drive builds the rotor flux at standstill for
   ``control.premagnetise_T2`` rotor time constants of its model, ``T̂2 = L̂2 / R̂2(0)``
   (3: the flux at 95 % of its reference, ``1 - e^-3``), before it releases the speed
   reference. A speed reference that first leaves its initial value earlier than that is
   delayed, and with it the load profile (the duty cycle starts when the drive is ready) and
   the run's end (``simulation.t_end_s`` counts the duty cycle: the run lasts
   ``t_end_s + delay_s``). On Table IV (T2 = 87 ms) the presets' 0.5 s of magnetisation is
   5.7 T2 and nothing moves; on Krause 2250 hp (T2 = 1.6 s) the duty cycle starts 4.3 s later.
   A reference that starts away from zero (a running start) is not delayed.
   With the standstill R1 identification (``mras.R1_standstill``) the premagnetisation *is*
   the test's standstill: the test measures the flux build-up and takes its window while
   the drive magnetises, and when the build-up the drive measures is not over by the end of
   the premagnetisation the drive keeps magnetising until the test has its window (at most
   ``mras.R1_standstill_hold_T2``), the whole duty cycle, speed reference and load, waiting
   for it (:func:`imdrive.kernels.stages.profiles`, ``t_hold``). That end is measured, not
   guessed: a fixed 4 T̂2 per current level was 1.7 T2 too long per level from R̂2(0) =
   0.6 R2 and short from R̂2(0) > R2, where the kernel held the speed reference alone and a
   load step stated after its start overtook it (Krause 2250 hp: the drive at standstill
   pulled to -300 rpm). This time is not added to the run's end.
   R2 tracking's start, ``compensator.t_on_s`` (its injection's too), is a time of the duty
   cycle and moves with it, by the delay and the test's wait alike
   (:func:`imdrive.run.compensator_blocks.tracking_start_s`, ``t_hold``): it stood at its
   absolute time before, and on Krause 2250 hp ``injection-robust``'s compensator started
   1.7 s before the speed reference left zero, not 3.5 s after it as on Table IV.
2. **Torque-limited ramps** (``control.ramp_torque_limit``). A ramp of the speed reference
   steeper than the machine can follow at the drive's torque limit is followed at
   :data:`RAMP_TORQUE_SHARE` of the acceleration that limit leaves over the load,
   ``a = share (T_max(n) - |T_L|) / J``, as a drive's ramp generator does; the reference
   then joins the profile where it meets it. ``T_max`` is the controller's torque at its
   current limit and reference flux, ``1.5 n_p (M̂/L̂2) ψ* √(I_max² - (ψ*/M̂)²)``, above the
   rated speed ``n_r`` at constant power (``× n_r/|n|``) and at most the breakdown torque at
   rated voltage (``T_bd (n_r/n)²``), taken at the ramp's highest speed; ``|T_L|`` is the
   largest load of the ramp's time span (its profile, viscous and fan terms). Steps are left
   as given (a step is a test of the speed loop; its following at the limit is told apart
   from a loss of control by :func:`imdrive.run.metrics.lost_control_time`).

Open loop, an imposed speed and ``drive.mode = "open-loop"`` are not sequenced (the
profiles are only resolved from per-unit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from imdrive.config.profile_units import stated_load_Nm, stated_speed_ref_rpm
from imdrive.config.profiles import Profile
from imdrive.errors import ConfigError

__all__ = [
    "DEFAULT_WINDOW_S",
    "Sequence",
    "sequence",
    "settled_at_s",
    "stated_load_Nm",
    "stated_speed_ref_rpm",
]

#: the steady-state window of the metrics and the status by default, s
DEFAULT_WINDOW_S = 0.5

#: share of the torque limit's acceleration a limited ramp is followed at: the speed PI keeps
#: the rest to correct its error (at the full limit it integrates a lag it cannot recover)
RAMP_TORQUE_SHARE = 0.9


@dataclass(frozen=True)
class LimitedRamp:
    """A ramp of the speed reference followed at the torque limit.

    Attributes
    ----------
    t0_s, t1_s : float
        Its start and end as the profile gives them (after the premagnetisation delay), s.
    from_rpm, to_rpm : float
        Its start and end speeds, rpm.
    acceleration_rpm_s : float
        The acceleration it is followed at, rpm/s.
    reached_s : float
        When the reference reaches ``to_rpm`` (or the profile again), s.
    torque_limit_Nm : float
        The torque limit at its highest speed, N m.
    """

    t0_s: float
    t1_s: float
    from_rpm: float
    to_rpm: float
    acceleration_rpm_s: float
    reached_s: float
    torque_limit_Nm: float

    def text(self) -> str:
        """One line for the console and the verdict."""
        return (
            f"the ramp {self.from_rpm:.4g} -> {self.to_rpm:.4g} rpm over "
            f"{self.t1_s - self.t0_s:.3g} s was followed at the torque limit "
            f"({self.torque_limit_Nm:.3g} N m; {self.acceleration_rpm_s:.3g} rpm/s), reaching "
            f"it at t = {self.reached_s:.3g} s"
        )


@dataclass(frozen=True)
class Sequence:
    """The resolved duty cycle of a scenario (module docstring).

    Attributes
    ----------
    speed_ref_rpm : Profile
        The speed reference the drive follows, rpm (per-unit resolved, delayed, ramps limited).
    load_Nm : Profile
        The load torque's profile, N m (per-unit resolved, delayed).
    premagnetise_s : float
        The premagnetisation time, s (0 when not sequenced).
    delay_s : float
        How much later the duty cycle starts than the profiles say, s.
    t_end_s : float
        The run's end, ``simulation.t_end_s + delay_s``, s.
    limited : tuple of LimitedRamp
        The ramps followed at the torque limit.
    """

    speed_ref_rpm: Profile
    load_Nm: Profile
    premagnetise_s: float = 0.0
    delay_s: float = 0.0
    t_end_s: float = math.nan
    limited: tuple[LimitedRamp, ...] = ()

    def n_steps(self, Ts: float) -> int:
        """Control periods of the run, ``round(t_end_s / Ts)``."""
        return int(round(self.t_end_s / Ts))

    def as_dict(self) -> dict:
        """JSON-ready (``summary.json``'s ``"sequence"``)."""
        return {
            "premagnetise_s": self.premagnetise_s,
            "delay_s": self.delay_s,
            "t_end_s": self.t_end_s,
            "limited_ramps": [r.text() for r in self.limited],
        }


def first_move_s(profile: Profile) -> float | None:
    """The time the profile first leaves its initial value, s (None: it never does)."""
    pts = profile.points
    for (t0, v0), (_, v1) in zip(pts, pts[1:], strict=False):
        if v1 != v0:
            return t0
    return None


def _delayed(profile: Profile, d: float) -> Profile:
    if d <= 0.0 or len(profile.points) == 1:
        return profile
    return Profile(tuple((t + d, v) for t, v in profile.points))


def sequence(sc) -> Sequence:
    """The scenario's duty cycle as the drive follows it (module docstring); memoised.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    Sequence

    Raises
    ------
    ConfigError
        A per-unit profile on a machine without a rated point.
    """
    memo = getattr(sc, "_sequence", None)
    if memo is not None:
        return memo
    out = _sequence(sc)
    try:
        object.__setattr__(sc, "_sequence", out)
    except (AttributeError, TypeError):  # a stand-in in a test: no memo
        pass
    return out


def _sequence(sc) -> Sequence:
    speed = stated_speed_ref_rpm(sc)
    load = stated_load_Nm(sc)
    t_end = sc.simulation.t_end_s
    sequenced = sc.drive.mode == "vector" and sc.plant.speed_mode != "imposed"
    if not sequenced:
        return Sequence(speed, load, t_end_s=t_end)
    from imdrive.config.perunit import resolve

    D = resolve(sc)
    T2_hat = (D.Ll2_hat + D.M_hat) / D.R2_hat
    t_mag = sc.control.premagnetise_T2 * T2_hat  # the R1 test extends it in the kernel
    first = first_move_s(speed)
    delay = 0.0
    if first is not None and speed.points[0][1] == 0.0 and first < t_mag:
        delay = t_mag - first
        speed, load = _delayed(speed, delay), _delayed(load, delay)
    limited: tuple[LimitedRamp, ...] = ()
    if sc.control.ramp_torque_limit:
        speed, limited = limit_ramps(speed, load, _TorqueLimit(sc, D))
    return Sequence(speed, load, t_mag, delay, t_end + delay, limited)


class _TorqueLimit:
    """The acceleration the drive's torque limit leaves over the load (module docstring)."""

    def __init__(self, sc, D):
        from imdrive.config.rated import rated_point_or_none

        psi = sc.control.flux_ref_Wb.points[0][1] if sc.control.flux_ref_Wb else D.psi_rated
        L2 = D.Ll2_hat + D.M_hat
        i_d = psi / D.M_hat
        i_q = math.sqrt(max(D.current_limit_A**2 - i_d**2, 0.0))
        self.T_max = 1.5 * sc.machine.pole_pairs * D.M_hat / L2 * psi * i_q
        rp = rated_point_or_none(sc.machine)
        self.n_rated = rp.speed_rpm if rp is not None else math.inf
        self.T_bd = rp.breakdown_torque_Nm if rp is not None else math.inf
        self.J = sc.machine.J_kgm2
        self.viscous, self.fan = sc.load.viscous_Nms, sc.load.fan_Nms2

    def torque_Nm(self, n_rpm: float) -> float:
        x = abs(n_rpm) / self.n_rated
        if x <= 1.0:
            return self.T_max
        return min(self.T_max / x, self.T_bd / (x * x))

    def acceleration_rpm_s(self, n_rpm: float, load_Nm: float) -> float:
        """``share (T_max(n) - |T_L|) / J`` in rpm/s (0 when the load takes it all)."""
        w = abs(n_rpm) * math.pi / 30.0
        T_L = abs(load_Nm) + self.viscous * w + self.fan * w * w
        a = RAMP_TORQUE_SHARE * (self.torque_Nm(n_rpm) - T_L) / self.J
        return max(a, 0.0) * 30.0 / math.pi


def _largest_load(load: Profile, t0: float, t1: float) -> float:
    vals = [abs(load(t0)), abs(load(t1))]
    vals += [abs(v) for t, v in load.points if t0 <= t <= t1]
    return max(vals)


def limit_ramps(speed: Profile, load: Profile, lim) -> tuple[Profile, tuple[LimitedRamp, ...]]:
    """The speed reference with every ramp steeper than ``lim`` allows followed at its limit.

    A rate limiter on the piecewise-linear profile, walked from breakpoint to breakpoint: a
    ramp segment's reference moves towards the profile at ``lim.acceleration_rpm_s`` (at the
    segment's highest speed and largest load) and follows it again where it meets it; a step
    (two breakpoints at one time) is passed through. A profile with no ramp too steep is
    returned as it is (the same object: bit for bit the same run).

    Parameters
    ----------
    speed, load : Profile
        The speed reference (rpm) and the load (N m).
    lim : object
        ``acceleration_rpm_s(n_rpm, load_Nm)`` and ``torque_Nm(n_rpm)``.

    Returns
    -------
    Profile, tuple of LimitedRamp
    """
    pts = speed.points
    rates = []
    for (t0, v0), (t1, v1) in zip(pts, pts[1:], strict=False):
        if t1 > t0 and v1 != v0:
            n_top = max(abs(v0), abs(v1))
            a = lim.acceleration_rpm_s(n_top, _largest_load(load, t0, t1))
            rates.append(a)
        else:
            rates.append(math.inf)
    steep = [
        abs(v1 - v0) / (t1 - t0) > a
        for ((t0, v0), (t1, v1)), a in zip(zip(pts, pts[1:], strict=False), rates, strict=True)
        if t1 > t0
    ]
    if not any(steep):
        return speed, ()
    out = [pts[0]]
    r = pts[0][1]
    notes = []
    open_note = None
    for k, ((ta, ua), (tb, ub)) in enumerate(zip(pts, pts[1:], strict=False)):
        if tb == ta:  # a step: passed through (a repeated breakpoint: nothing)
            if ub != ua:
                r = ub
                out.append((tb, ub))
            continue
        s = (ub - ua) / (tb - ta)
        a = rates[k] if math.isfinite(rates[k]) else _hold_rate(lim, ub, load, ta, tb)
        t = ta
        eps = 1e-9 * max(abs(ua), abs(ub), 1.0)
        while t < tb:
            u = ua + s * (t - ta)
            if abs(r - u) <= eps and abs(s) <= a:  # on the profile, and it can follow
                r, t = ub, tb
                out.append((tb, ub))
                break
            sigma = math.copysign(1.0, u - r) if abs(r - u) > eps else math.copysign(1.0, s)
            if open_note is None:
                open_note = (ta, tb, r, ub, a)
            rate = sigma * a - s
            dt = (u - r) / rate if abs(r - u) > eps and rate != 0.0 else math.inf
            if dt <= 0.0 or t + dt >= tb:
                r += sigma * a * (tb - t)
                t = tb
                out.append((tb, r))
                break
            t += dt
            r = u + s * dt
            out.append((t, r))
            notes.append(_note(open_note, t, lim))
            open_note = None
    t_last, v_last = pts[-1]
    if abs(r - v_last) > 1e-9 * max(abs(v_last), 1.0):  # still behind after the last point
        a = _hold_rate(lim, v_last, load, t_last, math.inf)
        t_reach = t_last + abs(v_last - r) / a if a > 0.0 else math.inf
        if not math.isfinite(t_reach):
            raise ConfigError(
                "control.speed_ref_rpm",
                f"the load leaves no torque to accelerate to {v_last:.4g} rpm at the current "
                "limit (control.current_limit_A)",
            )
        out.append((t_reach, v_last))
        if open_note is None:
            open_note = (t_last, t_last, r, v_last, a)
        notes.append(_note(open_note, t_reach, lim))
    elif open_note is not None:
        notes.append(_note(open_note, out[-1][0], lim))
    return Profile(tuple(out)), tuple(notes)


def _hold_rate(lim, n_rpm: float, load: Profile, ta: float, tb: float) -> float:
    """The limit's acceleration while the reference catches up with a level of ``n_rpm``."""
    tb = ta if not math.isfinite(tb) else tb
    T_L = max(_largest_load(load, ta, tb), abs(load.final))
    return lim.acceleration_rpm_s(n_rpm, T_L)


def _note(open_note, reached: float, lim) -> LimitedRamp:
    t0, t1, v0, v1, a = open_note
    return LimitedRamp(t0, t1, v0, v1, a, reached, lim.torque_Nm(max(abs(v0), abs(v1))))


#: ``a t / 2`` at which the speed loop's answer to a step, ``(1 + a t/2) e^(-a t/2)`` for the
#: default gains' double pole at ``-a/2`` (``a = 2 pi speed_bandwidth_Hz``), is down to 2 %
SETTLE_HALF_A_T = 5.83
#: the steady-state window is cut to start where the last transient has settled when at least
#: this share of it is left; else it is kept whole and the verdict says it had not settled
MIN_SETTLED_SHARE = 0.2


def settled_at_s(sc) -> float:
    """When the last change of the field-oriented drive's speed reference or load (the
    breakpoints of :func:`sequence`, the premagnetisation's delay and the torque-limited ramps
    included) has settled, s: ``t_last + 2 × 5.83 / a``, ``a = 2π speed_bandwidth_Hz``
    (:data:`SETTLE_HALF_A_T`; 0.37 s at 5 Hz); 0 for an open-loop drive or an imposed speed."""
    if sc.drive.mode != "vector" or sc.plant.speed_mode == "imposed":
        return 0.0
    from imdrive.config.perunit import speed_bandwidth_Hz

    seq = sequence(sc)
    t_last = max(seq.speed_ref_rpm.points[-1][0], seq.load_Nm.points[-1][0])
    if t_last <= 0.0:
        return 0.0
    return t_last + 2.0 * SETTLE_HALF_A_T / (2.0 * math.pi * speed_bandwidth_Hz(sc))
