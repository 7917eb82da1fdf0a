"""The observer's speed adaptation slows below a sixth of its bandwidth in stator frequency
(kernels/estimators/afo.py, ``adaptation_share``).

The claim: on Table IV's dead-time bridge (``envelope-full``'s inverter, 2 us compensated
with a 20 % error) at 0.1 of the rated speed without load, the sixth harmonic of the stator
frequency is 36 Hz; with the adaptation at its full 80 Hz there, the estimate ended 3.2-4.6
rpm off and R̂2 1.6-3.9 % off (the thermal ramp the larger); slowed to 40 Hz, 1.1-1.7 rpm
and under 1 %.
"""

import warnings

import pandas as pd
import pytest

from imdrive.studies import envelope


@pytest.mark.slow  # 4 closed-loop runs of 38 s, two on the switching bridge
def test_the_observer_drive_holds_R2_on_the_bridge_at_low_speed(tmp_path):
    sweep = envelope.reduced_sweep(tmp_path / "s.toml", speeds=(0.1,), loads=(0.0,))
    text = sweep.read_text().replace("[set]\n", '[set]\ncontrol.speed_feedback = "afo"\n', 1)
    sweep.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        envelope.run(
            tmp_path / "store", sweep_file=str(sweep), csv=tmp_path / "e.csv",
            figures=tmp_path / "f",
        )  # fmt: skip
    df = pd.read_csv(tmp_path / "e.csv")
    bridge = df[df["inverter"] == "bridge"]
    assert len(bridge) == 2
    assert (bridge["speed_error_rpm"].abs() < 2.5).all(), bridge.to_string()
    assert (bridge["R2_error_pct"].abs() < 1.5).all(), bridge.to_string()
