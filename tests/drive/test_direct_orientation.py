"""Direct field orientation on an observer's flux (kernels/ifoc.py, run/blocks.py
``DIRECT_ORIENTATION_FROM_PU``).

An estimator that observes the rotor flux (the AFO, the EKF) orients the drive's frame on it
above 0.1 of the rated stator frequency. The claim: accelerating to the rated speed from
R̂2(0) = 1.2 R2, the frame stays on the plant's rotor flux (its true angle, from the plant's
state), where the integrated slip, which follows R̂2, leaves it several degrees off on the
large machines and, with the EKF on Krause 2250 hp, loses control.
"""

import warnings

import numpy as np
import pytest

import imdrive.run.blocks as blocks
from imdrive.run.simulate import simulate
from imdrive.studies import machines as envm


def _ramp(machine: str, feedback: str):
    """Max |frame - rotor flux angle| (degrees) above 0.1 of the rated stator frequency on
    the ramp to the rated speed, no load, from R̂2(0) = 1.2 R2, and the run's verdict."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scs, _ = envm.scenarios(
            [machine], drives=["sensorless-afo"], speeds=(1.0,), loads=(0.0,), ratios=(1.2,)
        )
        sc = scs[0].with_overrides({"control.speed_feedback": feedback})
        res = simulate(sc)
    s = {k: np.asarray(v) for k, v in res.signals.items()}
    psi = s["psi_r_alpha_Wb"] + 1j * s["psi_r_beta_Wb"]
    err = np.angle(psi * np.exp(-1j * s["theta_e_rad"]), deg=True)
    f_s = s["speed_rpm"] / 60.0 * sc.machine.pole_pairs
    above = f_s > 0.1 * sc.machine.rated_frequency_Hz
    assert above.sum() > 100
    return float(np.abs(err[above]).max()), res.metrics()["verdict"]


@pytest.mark.parametrize("machine", ["krause-500hp", "krause-2250hp", "paper-table-iv"])
@pytest.mark.parametrize("feedback", ["afo", "ekf"])
def test_the_observer_drive_holds_its_frame_on_the_rotor_flux(machine, feedback):
    # measured: 0.7-1.7 degrees
    worst, verdict = _ramp(machine, feedback)
    assert worst < 2.0
    assert verdict != "lost-control"


def test_the_integrated_slip_alone_leaves_the_frame_off(monkeypatch):
    # the same ramps with the frame integrating the slip (the drive before the change):
    # the AFO 5.9 degrees off on Krause 2250 hp (7.2 with its speed adaptation at 8 times the
    # speed loop's bandwidth throughout), the EKF loses control there
    monkeypatch.setattr(blocks, "DIRECT_ORIENTATION_FROM_PU", 1e9)
    worst, _ = _ramp("krause-2250hp", "afo")
    assert worst > 3.0
    _, verdict = _ramp("krause-2250hp", "ekf")
    assert verdict == "lost-control"
