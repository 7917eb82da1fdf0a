"""Standstill identification of R1 by the drive, at one or two current levels, while it
magnetises (``mras.R1_standstill``, ``mras.R1_standstill_levels``), whatever its speed
estimator.

A controller block: its parameters and state are fields of the controller's records
(:data:`R1_STANDSTILL_PARAMS` in ``CONTROL_PARAMS``, :data:`R1_STANDSTILL_STATE` in
``CONTROL_STATE``), it writes the controller's model (``R1_hat``, and what the flux reference
and the duty cycle's hold read: ``dc_boost``, ``dc_busy``), and the engine runs it after the
estimator's step (:func:`imdrive.kernels.stages.estimate`). Until 2026-11-29 it lived in the
MRAS's records, so only the MRAS family identified R1 at standstill; the estimator whose
models integrated through the test is told to restart them the period after the test set
R1_hat (``EstimatorInput.restart``; the MRAS's voltage model, :func:`restart_after_test`).

One level (:func:`mras_r1_standstill`) is the DC test of IEEE Std 112 made by the drive on
every start: at a constant flux current ``v = R1 i``. On a real inverter the voltage the
controller knows is off by what its dead-time compensation leaves, nearly a constant voltage
along the current at standstill (Jeong & Park, IEEE Trans. Ind. Electron. 38(2), 1991), so one
level reads ``R1 + u0/|i|``: 1.57 R1 on the envelope's bridge (2 us dead time compensated as
1.6 us). Two levels (:func:`r1_two_levels`) cancel it: at two settled currents ``I_A``,
``I_B`` along the same axis, ``R1 = (u_A - u_B)/(I_A - I_B)`` and the residual ``u0 = u_B - R1
I_B`` (Holtz & Quan, "Sensorless vector control of induction motors at very low speed using a
nonlinear inverter model and parameter identification", IEEE Trans. Ind. Appl. 38(4), 2002).
The residual then starts the online scale of the dead-time compensation
(:func:`imdrive.kernels.inverter_scale.start_from_identified`), which cannot adapt below its
sixth harmonic's lowest frequency (at 20 rpm, never).

The build-up left in a window is fitted as the decay at the T2 the drive measured on it
(both tests). Until 2026-11-24 the one-level test fitted the controller's current-model
build-up ``g = (M/L2) p lam_hat``, whose shape is T2_hat's: R1_hat then carried R2_hat(0)'s
error, -0.9 / +0.5 % on Table IV and -1.7 / +1.4 % on Krause 50 hp from R2_hat(0) = 0.6 /
1.4 R2 (machine envelope, ideal drive), and at 10 % of the rated speed regenerating the
rated torque the injection compensator's R2_hat ended +2.2 % off from 0.7 R2 on Krause
50 hp for R1_hat's -1.5 %. With the measured decay (same runs, six library machines,
R2_hat(0) = 0.6-1.4 R2) R1_hat is within 0.03 %; on a saturating machine, whose build-up is
not one exponential, -0.2 to -1.5 % (with ``g``: -0.1 to -2.0 %). ``g`` stays the regressor
when no T2 was measured (a build-up below the 1 % block threshold).

The cost is magnetisation time: each level waits for its flux build-up (3.5 measured T2) and
takes a window of half a T2_hat, so the test lasts 7-9.5 T2 from the start of magnetisation
(measured on the envelope's bridge from R2_hat(0) = 0.6-1.4 R2: Table IV 7.9-9.4, Aalto
2.2 kW 6.9-8.9, Krause 50 hp 7.2-9.3 T2), against 4-5 T2 for one level; the speed reference
waits for it (on Table IV 2.2-3.7 T2 past the 0.5 s magnetisation of the presets). The first
level is 0.6 of the flux reference: below saturation and far from the current limit (1.5
drove the uncommissioned realistic machine into saturation, where its sensorless standstill
wandered), and the difference ``I_B - I_A = 0.4 I_B`` multiplies each level's error by 1.5
(``I_A/(I_B - I_A)``) and 2.5 (``I_B/(I_B - I_A)``).
"""

from __future__ import annotations

import math

from imdrive.kernels.jit import njit
from imdrive.kernels.records import b1, f8

#: Shortest window of the standstill identification, s (shorter runs leave R1_hat alone).
R1_DC_MIN_WINDOW = 0.05

#: Its parameters, fields of the controller's ``CONTROL_PARAMS``.
R1_STANDSTILL_PARAMS = [
    ("R1_dc", b1),  # standstill R1 identification while magnetising (0: off)
    ("R1_dc_settle", f8),  # shortest time from the start of a standstill run to its window, s
    ("R1_dc_block", f8),  # block over which the measured build-up is compared, s
    ("R1_dc_nT2", f8),  # the window opens this many measured rotor time constants in
    ("R1_dc_levels", f8),  # 1 or 2 current levels
    ("R1_dc_boost", f8),  # level A's flux reference is 1 + this times the reference's
    ("R1_dc_hold", f8),  # the speed reference waits for the standstill test at most this, s
    ("R1_dc_min", f8),  # clamps of the identified R1_hat, ohm
    ("R1_dc_max", f8),
]

#: Its state, fields of the controller's ``CONTROL_STATE``.
R1_STANDSTILL_STATE = [
    ("dc_t", f8),  # time in the present standstill run's level, s
    ("dc_vi", f8),  # its window's sums for the least squares: x1 y (x1 = |i|^2,
    ("dc_ii", f8),  # x1 x1            y = Re(u conj i), x2 = |i|^2 exp(-t/T2), see
    ("dc_gi", f8),  # x1 x2            r1_standstill)
    ("dc_gg", f8),  # x2 x2
    ("dc_gy", f8),  # x2 y
    ("dc_n", f8),  # samples in the window
    ("dc_by", f8),  # the present block's sum of y = Re(u conj i)
    ("dc_bx", f8),  # and of |i|^2
    ("dc_bt", f8),  # its duration so far, s
    ("dc_r_prev", f8),  # apparent resistance of the last block (0: none yet), ohm
    ("dc_r_prev2", f8),  # and of the one before (0: none yet), ohm
    ("dc_r_first", f8),  # and of the run's first block (0: none yet), ohm
    ("dc_T2", f8),  # the rotor time constant measured from the build-up's decay, s
    ("dc_d01", f8),  # sum of the products of successive block differences, ohm^2
    ("dc_d00", f8),  # and of the squares of the earlier ones (T2's least squares), ohm^2
    ("dc_open", b1),  # the window is open: the measured flux build-up is over
    ("dc_status", f8),  # 0 no standstill run yet, 1 R1 identified, 2 could not, 3 one level
    ("dc_run_t", f8),  # the standstill run's time, s
    ("dc_phase", f8),  # the two-level test: 0 level A, 1 level B, 2 B's window, 3 done
    ("dc_rA", f8),  # level A's apparent resistance, ohm
    ("dc_iA", f8),  # and current, A
    ("dc_T2A", f8),  # and the T2 measured on its build-up, s
    ("dc_restart", b1),  # a level was identified at this sample: the estimator restarts
    ("dc_su_alpha", f8),  # the present sub-block's sums of v (V) and of the period's mean
    ("dc_su_beta", f8),  # current (A), and its number of periods (sub_block_periods)
    ("dc_si_alpha", f8),
    ("dc_si_beta", f8),
    ("dc_sn", f8),
]


@njit(cache=True)
def _r1_window_opens(p, s, y, i2, Ts):
    """One sample of the measured flux build-up (:func:`mras_r1_standstill`): block sums of
    ``y = Re(u conj i)`` and ``|i|^2``; at each block's end the apparent resistance ``r_b``,
    the plant's T2 from the decay ratio of its differences, and ``s.dc_open`` once the
    build-up measured has decayed by ``p.R1_dc_nT2`` time constants: the geometric tail left
    after the block, ``|r_b - r_prev| q/(1 - q)`` (``q = exp(-block/T2)``), is at most
    ``exp(-p.R1_dc_nT2)`` of the build-up since the first block, ``r_first - r_b + tail``; or
    two blocks in a row have moved by less than 1 % (the build-up below the current ripple's
    noise, or over before the run began). The first block holds the current's rise and is
    not compared.

    T2 is the least-squares decay ratio of all the block differences, ``q = sum d0 d1 / sum
    d0^2``: large differences, measured well above the noise, weigh most. Until 2026-11-30 it
    was the mean of the block-wise ``-block / ln(d1/d0)``, and a late pair of small, noisy
    differences (``q`` near 1) threw it: on the realistic presets' drive (sensor noise
    20 mA) level A's T2 ranged 0.083-0.217 s over eight noise seeds on Table IV from 1.2 R2,
    and R1_hat followed it (-6 … +5 %); with the least squares 0.085-0.100 s."""
    s.dc_by += y
    s.dc_bx += i2
    s.dc_bt += Ts
    if s.dc_bt < p.R1_dc_block:
        return
    r_b = s.dc_by / s.dc_bx
    if s.dc_r_first == 0.0:  # the first block holds the current's rise: not compared
        s.dc_r_first = r_b
        s.dc_by = 0.0
        s.dc_bx = 0.0
        s.dc_bt = 0.0
        return
    if s.dc_r_prev2 > 0.0:
        # the decay ratio of the build-up over one block: exp(-block / T2)
        d0 = s.dc_r_prev - s.dc_r_prev2
        d1 = r_b - s.dc_r_prev
        # the least squares of d1 = q d0 over the blocks so far: a late, noisy pair of
        # small differences barely moves it
        s.dc_d01 += d0 * d1
        s.dc_d00 += d0 * d0
        q_ls = s.dc_d01 / s.dc_d00 if s.dc_d00 > 0.0 else 0.0
        if 0.0 < q_ls < 1.0:
            s.dc_T2 = -s.dc_bt / math.log(q_ls)
        flat = abs(d1) <= 0.01 * abs(r_b)
        # the tail at the measured T2 (before one is measured, at the block's T2_hat, four)
        T2 = s.dc_T2 if s.dc_T2 > 0.0 else 4.0 * p.R1_dc_block
        q_T2 = math.exp(-s.dc_bt / T2)
        tail = abs(d1) * q_T2 / (1.0 - q_T2)
        decayed = tail <= math.exp(-p.R1_dc_nT2) * abs(s.dc_r_first - r_b + tail)
        still = flat and abs(d0) <= 0.01 * abs(r_b)
        if s.dc_t >= p.R1_dc_settle and (decayed or still):
            s.dc_open = True
    s.dc_r_prev2 = s.dc_r_prev
    s.dc_r_prev = r_b
    s.dc_by = 0.0
    s.dc_bx = 0.0
    s.dc_bt = 0.0


@njit(cache=True)
def _window_solve(s):
    """The window's least squares ``y = R1 x1 + k x2`` (:func:`mras_r1_standstill`), ohm: ``k``
    scales the build-up's regressor (the decay at the T2 measured, or the model's build-up) to
    the plant's; where the two cannot be told apart (the model's build-up over, ``x2 ~ 0``)
    ``y = R1 x1 + x2`` (``k = 1``)."""
    det = s.dc_ii * s.dc_gg - s.dc_gi * s.dc_gi
    if det > 1e-6 * s.dc_ii * s.dc_gg and s.dc_gg > 0.0:
        return (s.dc_vi * s.dc_gg - s.dc_gi * s.dc_gy) / det
    return (s.dc_vi - s.dc_gi) / s.dc_ii


#: Sub-blocks per block of the measured build-up (:func:`sub_block_periods`).
R1_DC_SUB_PER_BLOCK = 8


@njit(cache=True)
def sub_block_periods(p, Ts):
    """Periods per sub-block of the standstill test: an eighth of ``p.R1_dc_block`` (a
    quarter of T2_hat), at least one (:func:`r1_standstill`: why means). A quarter or a
    sixteenth of a block gave the same spread of R1_hat on the realistic drive (0.3-1.2 %
    against 0.3-1.1 %): the window's length, not the sub-block's, sets it."""
    return max(1.0, math.floor(p.R1_dc_block / (R1_DC_SUB_PER_BLOCK * Ts) + 0.5))


@njit(cache=True)
def _clear_sub_block(s):
    """Start a new sub-block: its sums from zero."""
    s.dc_su_alpha = 0.0
    s.dc_su_beta = 0.0
    s.dc_si_alpha = 0.0
    s.dc_si_beta = 0.0
    s.dc_sn = 0.0


@njit(cache=True)
def _sub_block_sample(p, s, Ts_sub):
    """One sub-block's means into the build-up detector or the window's least squares
    (:func:`r1_standstill`), the sub-block standing for one sample of ``Ts_sub`` seconds."""
    n = s.dc_sn
    u_alpha = s.dc_su_alpha / n
    u_beta = s.dc_su_beta / n
    i_alpha = s.dc_si_alpha / n
    i_beta = s.dc_si_beta / n
    _clear_sub_block(s)
    i2 = i_alpha * i_alpha + i_beta * i_beta
    y = u_alpha * i_alpha + u_beta * i_beta
    two = p.R1_dc_levels == 2
    T2_A = s.dc_T2A if two and s.dc_phase >= 1.0 else 0.0  # level B: A's T2 (r1_two_levels)
    if not s.dc_open and T2_A > 0.0:
        s.dc_open = s.dc_t >= p.R1_dc_nT2 * T2_A
    elif not s.dc_open:  # the measured build-up: compare block by block
        _r1_window_opens(p, s, y, i2, Ts_sub)
    else:
        x1 = i2  # |i|^2, the regressor of R1
        # the build-up left decays at the T2 measured on it (T2_hat's before one is)
        T2_m = T2_A if T2_A > 0.0 else s.dc_T2
        if T2_m <= 0.0:
            T2_m = 4.0 * p.R1_dc_block
        x2 = x1 * math.exp(-s.dc_n * Ts_sub / T2_m)  # the build-up's power (k's regressor)
        s.dc_vi += x1 * y
        s.dc_ii += x1 * x1
        s.dc_gi += x1 * x2
        s.dc_gg += x2 * x2
        s.dc_gy += x2 * y
        s.dc_n += 1.0


@njit(cache=True)
def _reset_level(s):
    """Start a new level: the block detector and the window's sums from zero."""
    s.dc_t = 0.0
    s.dc_by = 0.0
    s.dc_bx = 0.0
    s.dc_bt = 0.0
    s.dc_r_prev = 0.0
    s.dc_r_prev2 = 0.0
    s.dc_r_first = 0.0
    s.dc_T2 = 0.0
    s.dc_d01 = 0.0
    s.dc_d00 = 0.0
    s.dc_open = False
    s.dc_vi = 0.0
    s.dc_ii = 0.0
    s.dc_gi = 0.0
    s.dc_gg = 0.0
    s.dc_gy = 0.0
    s.dc_n = 0.0


@njit(cache=True)
def r1_standstill(
    p, m, s, v_alpha, v_beta, i_prev_alpha, i_prev_beta, i_alpha, i_beta, w_ref, w_e, Ts
):
    """Standstill R1 identification while the flux builds up (``p.R1_dc``; updates ``m.R1_hat``).

    With the speed reference at zero and a DC flux current, the stator equation in steady
    state is ``v = R1 i``: the flux is constant and no current changes, so neither the
    ``sigma L1 p i`` nor the ``p psi`` term is left (the DC test of IEEE Std 112, made by the
    drive on every start). What is left of the flux build-up in the window (after four rotor
    time constants still about 5 % of ``R1 i``) is a regressor with a free scale ``k``: the
    decay ``exp(-t/T2)`` at the T2 the drive *measured* on the build-up (below), one
    exponential whatever R2_hat is; at T2_hat (the controller's current-model build-up's
    shape) only where no T2 was measured (module docstring: why, and what each gave).

    A standstill run is a stretch of periods with ``w_ref = 0``, ``|i| > 1 A`` and
    ``|w_e| < 2 pi 0.5 Hz``. Its window opens when the flux build-up *measured* is nearly
    over: the run is cut into blocks of ``p.R1_dc_block`` seconds (a quarter of the
    controller's T2_hat) and each block's apparent resistance ``r_b = sum Re(v conj i) /
    sum |i|^2`` is ``R1`` plus the build-up's ``(M/L2) p psi . i / |i|^2``, which decays as
    ``exp(-t/T2)`` with the *plant's* T2. The ratio of two successive block differences is ``q =
    exp(-block/T2)``, so ``T2 = -block / ln q`` is measured (``q`` the least squares over the
    blocks, :func:`_r1_window_opens`). The window opens when the build-up *left* is
    ``exp(-p.R1_dc_nT2)`` (3.5: 3 %) of the build-up seen since the first block, the tail after the
    last block taken as a geometric series of its difference, ``|r_b - r_prev| q/(1 - q)``, or when
    two blocks in a row move by less than 1 % (and not before ``p.R1_dc_settle``, one T2_hat): the
    decay the drive measures, whatever shape it has. A window fixed at four T2_hat fell after the
    0.5 s magnetisation whenever R2_hat(0) <= 0.76 R2; one at 3.5 times the mean measured
    T2 fell after it on a saturating machine, whose build-up is slow at first (unsaturated)
    and fast at the end: on the realistic drive (Table IV, 2 us dead time compensated as
    1.6 us, 1 V device drops, sensor errors, saturation) the mean was 0.117 s against the
    0.087 s of the machine's data, the window opened at 0.44 s and lasted less than
    :data:`R1_DC_MIN_WINDOW` from R2_hat(0) = 1.2 and 1.4 R2 (on the Aalto 2.2 kW machine at
    every R2_hat(0) from 0.6 to 1.4 R2); with the decay measured it opens near 0.3 s (the
    build-up left is fitted by the ``k x2`` term below). When the
    run ends (the speed reference leaves zero) and its window lasted at least
    :data:`R1_DC_MIN_WINDOW`, R1_hat is the least-squares solution over the window of::

        Re(v conj i) = R1 |i|^2 + k x2,
        x2 = |i|^2 exp(-t/T2)   (T2 measured, else T2_hat = 4 p.R1_dc_block)

    (``t`` from the window's start) clamped to ``[p.R1_dc_min, p.R1_dc_max]``. ``v``: the
    voltage applied over the last period as the controller knows it (commanded, less any
    dead-time compensation), V; ``i``: the mean of the period's two current samples, A; both as
    means over sub-blocks of an eighth of a block (:func:`sub_block_periods`), which the blocks
    and the window take as their samples. The current is held constant, so ``sigma L1 p i``
    averages to nothing over a sub-block; until 2026-11-30 the test subtracted it period by
    period, from the *measured* current, whose noise then made it the largest term of each
    sample, and multiplied ``v`` and ``i`` period by period, whose noise is correlated through
    the current controller. On the realistic presets' drive (sensor noise 20 mA, 12-bit ADC; two
    levels; eight noise seeds on Table IV, the Aalto 2.2 kW machine and Krause 50 hp from
    R2_hat(0) = 0.8 and 1.2 R2) R1_hat's spread (standard deviation per case) was 1.0-8.8 %, its
    worst error 20.6 %, and three of the 48 tests identified level A only; with the means and
    the least-squares T2 (:func:`_r1_window_opens`) 0.3-1.1 %, at most 2.4 %, and every test
    both levels. On the ideal drive (seven library machines, R2_hat(0) = 0.6-1.4 R2) within
    0.016 % (0.033 % before). With the ideal (average) inverter the identification is exact. On
    a real inverter the dead time's voltage error left after compensation adds ``dv/|i|`` to the
    result, and at standstill ``R1 |i|`` is only a few volts: measured on
    ``sensorless-realistic`` (2 us dead time, compensated for 1.6 us) R1_hat came out 1.9 R1.
    The test at two current levels (``p.R1_dc_levels = 2``, :func:`r1_two_levels`) removes that
    bias.

    The first start waits for the window (as the two-level test's does): until R1_hat has
    been identified once, the speed reference is held at zero (``m.dc_busy``, at most
    ``p.R1_dc_hold``) while the window is shorter than :func:`level_window`. Without the wait
    a magnetisation shorter than the build-up measured plus a window left R1_hat as it was:
    the machine envelope's four rotor time constants on Krause's 50 hp machine (the window
    opens about 3.7 T2 into the run, at a block's end, and the ramp began at 4 T2), where
    R1_hat then stayed 10 % off and the injection compensator's R2_hat 6-9 % off at 10 % of
    the rated speed regenerating. Measured with the wait (sensorless, one level, R2_hat(0)
    = 0.8 R2, reference leaving zero at 3 T2): the start moves to 4.7 T2 on Table IV and on
    Krause 50 hp, R1_hat -0.6 / -0.8 % off (tests/drive/test_r1_standstill_wait.py).

    ``s.dc_status`` says what the last run did: 1 R1_hat identified, 2 the run ended before
    a window of :data:`R1_DC_MIN_WINDOW` (the build-up was not over: a magnetisation too
    short for the machine's T2), R1_hat left as it was, 3 (two levels) only the first level
    was identified: R1_hat holds the inverter's residual as with one level (logged as
    ``R1_id_status``). ``s.dc_restart`` is set for the one period after the test set R1_hat
    (the engine hands it to the estimator, ``EstimatorInput.restart``).
    """
    s.dc_restart = False
    still = w_ref == 0.0 and abs(w_e) < math.pi
    i_m_alpha = 0.5 * (i_alpha + i_prev_alpha)
    i_m_beta = 0.5 * (i_beta + i_prev_beta)
    i2 = i_m_alpha * i_m_alpha + i_m_beta * i_m_beta
    two = p.R1_dc_levels == 2
    if two and s.dc_phase >= 3.0:  # the two-level test is made once, at the first start
        return
    Ts_sub = sub_block_periods(p, Ts) * Ts  # the sub-block, the test's sample
    if still and i2 > 1.0:
        s.dc_t += Ts
        s.dc_run_t += Ts
        s.dc_su_alpha += v_alpha
        s.dc_su_beta += v_beta
        s.dc_si_alpha += i_m_alpha
        s.dc_si_beta += i_m_beta
        s.dc_sn += 1.0
        if s.dc_sn * Ts >= Ts_sub - 0.5 * Ts:
            _sub_block_sample(p, s, Ts_sub)
        if two:
            r1_two_levels(p, m, s, Ts_sub)
        elif not m.R1_id:  # the first start waits for one level's window too
            m.dc_busy = s.dc_n * Ts_sub < level_window(p)
            m.dc_hold_max = p.R1_dc_hold
        return
    m.dc_busy = False
    # the running drive has had no standstill sample since the last end: nothing to end
    if two or s.dc_t > 0.0 or s.dc_sn > 0.0:
        _run_end(p, m, s, two, Ts_sub)


@njit(cache=True)
def _run_end(p, m, s, two, Ts_sub):
    """A standstill run ended (:func:`r1_standstill`): R1_hat from its window (one level)
    or from both levels (:func:`_two_levels_end`), its status, and the sums from zero."""
    _clear_sub_block(s)
    if two:
        _two_levels_end(p, m, s, Ts_sub)
    elif s.dc_n * Ts_sub >= R1_DC_MIN_WINDOW and s.dc_ii > 0.0:
        m.R1_hat = min(max(_window_solve(s), p.R1_dc_min), p.R1_dc_max)
        m.R1_gate = m.R1_hat
        m.R1_id = True
        s.dc_status = 1.0
        s.dc_restart = True
    elif s.dc_t > 0.0:  # a standstill run ended without its window: say so
        s.dc_status = 2.0
    _reset_level(s)
    s.dc_run_t = 0.0


@njit(cache=True)
def level_window(p):
    """The window each level of the two-level test needs, s: half the controller's T2_hat
    (two blocks), at least :data:`R1_DC_MIN_WINDOW`."""
    return max(R1_DC_MIN_WINDOW, 2.0 * p.R1_dc_block)


@njit(cache=True)
def r1_two_levels(p, m, s, Ts):
    """One standstill sample of the two-level test (``p.R1_dc_levels = 2``; module docstring).

    Level A: the flux reference times ``1 + p.R1_dc_boost`` (``m.dc_boost``, which the control
    stage applies to ``psi_ref``) until the measured build-up is over and a window of
    :func:`level_window` is taken (:func:`_r1_window_opens`, then the least squares with the
    build-up's regressor, :func:`_window_solve`): its apparent resistance ``s.dc_rA`` and
    current ``s.dc_iA`` (``(sum |i|^4 / n)^(1/4)``), and the T2 measured on its build-up,
    ``s.dc_T2A``. In both windows the build-up left is fitted as ``exp(-t/T2)`` at the T2
    measured, not as the model's build-up at T2_hat (from R2_hat(0) = 0.6 and 1.4 R2 on Table
    IV that left R1_hat -4.8 and +4.2 % off with a first level at 1.5: the difference of the
    two levels multiplies each level's error by ``I/|I_A - I_B|``, 3 and 2). Level B: the flux
    reference itself; its step decays with the same T2 (a linear rotor circuit), so its window
    opens ``p.R1_dc_nT2`` times ``s.dc_T2A`` after the step (the block-wise decay of level B's
    smaller step read 0.59 s for 0.156 s on Krause's 50 hp from 1.4 R2, and R1_hat came out
    0.63 R1) and stays open until the run ends. Until level B's window is long enough the
    speed reference is held at zero (``m.dc_busy``; the engine shifts the speed profile by the
    time held, ``m.t_hold``) for at most ``p.R1_dc_hold`` seconds (``m.dc_hold_max``).
    ``s.dc_phase``: 0 level A, 1 level B, 2 level B's window long enough, 3 done.
    """
    if s.dc_phase == 0.0:
        m.dc_boost = p.R1_dc_boost
        if s.dc_n * Ts >= level_window(p) and s.dc_ii > 0.0:
            s.dc_rA = _window_solve(s)
            s.dc_iA = (s.dc_ii / s.dc_n) ** 0.25
            s.dc_T2A = s.dc_T2
            _reset_level(s)
            m.dc_boost = 0.0
            s.dc_phase = 1.0
    elif s.dc_phase == 1.0 and s.dc_n * Ts >= level_window(p):
        s.dc_phase = 2.0
    m.dc_busy = s.dc_phase < 2.0
    m.dc_hold_max = p.R1_dc_hold


@njit(cache=True)
def _two_levels_end(p, m, s, Ts):
    """The standstill run of the two-level test ended (:func:`r1_two_levels`): ``R1 = (r_A I_A
    - r_B I_B)/(I_A - I_B)`` into ``m.R1_hat`` (clamped to ``[p.R1_dc_min, p.R1_dc_max]``), the
    residual along the current ``u0 = (r_B - R1) I_B`` into ``m.u0_id`` at ``m.i_id = I_B``
    for the online inverter-error scale to start from (``m.ie_new``); ``m.R1_id`` stays false
    (R1_hat holds no residual). With level A only, R1_hat = r_A as one level would (status 3,
    ``m.R1_id``); with neither, R1_hat is left (status 2) and the next standstill run tries
    again (the test is made once it has identified a level)."""
    m.dc_busy = False
    m.dc_boost = 0.0
    if s.dc_run_t == 0.0:
        return
    if s.dc_phase >= 1.0:  # a level identified: the estimator restarts from standstill
        s.dc_restart = True
    if s.dc_phase >= 1.0 and s.dc_n * Ts >= R1_DC_MIN_WINDOW and s.dc_ii > 0.0:
        r_B = _window_solve(s)
        i_B = (s.dc_ii / s.dc_n) ** 0.25
        if abs(s.dc_iA - i_B) > 0.1 * i_B:
            r1 = (s.dc_rA * s.dc_iA - r_B * i_B) / (s.dc_iA - i_B)
            m.R1_hat = min(max(r1, p.R1_dc_min), p.R1_dc_max)
            m.R1_gate = m.R1_hat
            m.u0_id = (r_B - m.R1_hat) * i_B
            m.i_id = i_B
            m.ie_new = True
            s.dc_status = 1.0
            s.dc_phase = 3.0
            return
    if s.dc_phase >= 1.0:
        m.R1_hat = min(max(s.dc_rA, p.R1_dc_min), p.R1_dc_max)
        m.R1_gate = m.R1_hat
        m.R1_id = True
        s.dc_status = 3.0
        s.dc_phase = 3.0
    else:  # nothing identified: the next standstill run tries again
        s.dc_status = 2.0
