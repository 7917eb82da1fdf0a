"""Absolute / per-unit pairs of settings (``config/pairs.py``): an override of one member
replaces the other member the layer underneath carries, with a one-line note; both members in
one layer are refused, naming both."""

from __future__ import annotations

import re
import warnings

import pytest

from imdrive.cli import main
from imdrive.config.overrides import scenario_keys
from imdrive.config.pairs import PAIRS, pair_of, set_layer
from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError, ConfigWarning
from imdrive.sweep.spec import parse_sweep

KEYS = {k.dotted: k for k in scenario_keys()}
_PU = re.compile(r"_(pu|ratio)$")


def _unit(key: str):
    return (KEYS[key].info.json_schema_extra or {}).get("unit")


def _read(preset, *overrides):
    """The scenario and the ConfigWarnings its overrides gave."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        sc = Scenario.read(preset, list(overrides))
    return sc, [str(w.message) for w in seen if issubclass(w.category, ConfigWarning)]


# -- the table --------------------------------------------------------------------------------


@pytest.mark.parametrize("pair", PAIRS, ids=lambda p: p.per_unit[0])
def test_every_declared_pair_is_an_absolute_and_a_per_unit_key_of_one_section(pair):
    assert len(pair.absolute) == len(pair.per_unit) >= 1
    for a, u in zip(pair.absolute, pair.per_unit, strict=True):
        assert a in KEYS and u in KEYS, (a, u)
        assert a.rsplit(".", 1)[0] == u.rsplit(".", 1)[0]  # same section
        assert _unit(a), f"{a} has no unit: not an absolute value"
        assert _unit(u) is None, f"{u} has a unit: not per-unit"
        # (a run's length in R2 tracking's decision windows is a count, named as one)
        assert _PU.search(u) or u in ("smo_mras.speed_error_pu", "simulation.tracking_windows")
        # a member with a default of None is unset by default; the others default to a number
        # (a profile: the constant profile 0)
        for k in (a, u):
            d = KEYS[k].default
            assert d is None or isinstance(d, int | float) or d == Profile.constant(0.0), (k, d)
    assert pair.both in ("error", "per_unit", "absolute")


def test_each_key_is_in_one_pair_only():
    keys = [k for p in PAIRS for k in p.keys]
    assert len(keys) == len(set(keys))
    assert all(pair_of(k) is not None for k in keys)
    assert pair_of("control.speed_ref_rpm").per_unit == ("control.speed_ref_pu",)
    assert pair_of("control.current_limit_A") is None


def test_every_per_unit_key_with_an_absolute_twin_is_declared():
    """A ``X_pu`` / ``X_ratio`` key beside a key ``X_<unit>`` of the same section is a pair."""
    for key in KEYS:
        m = _PU.search(key)
        if not m:
            continue
        stem = key[: m.start()]
        twins = [k for k in KEYS if k.startswith(stem + "_") and k != key and _unit(k)]
        for t in twins:
            assert pair_of(t) is pair_of(key) is not None, f"{t} / {key} not in PAIRS"


# -- one override on a layer carrying the other member ---------------------------------------


def _table(data: dict, path: list[str]) -> dict:
    for p in path:
        data = data.setdefault(p, {})
    return data


@pytest.mark.parametrize("pair", PAIRS, ids=lambda p: p.per_unit[0])
@pytest.mark.parametrize("direction", ["absolute over per-unit", "per-unit over absolute"])
def test_setting_one_member_clears_the_other_with_a_note(pair, direction):
    new, old = (pair.absolute, pair.per_unit)
    if direction == "per-unit over absolute":
        new, old = old, new
    data: dict = {}
    for k in old:
        *sec, name = k.split(".")  # a section may be nested (plant.thermal)
        _table(data, sec)[name] = 123.0  # not a default of any member
    if pair.quiet:  # a profile is restated whole: cleared without a note
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            set_layer(data, [(tuple(new[0].split(".")), 7.0)])
        assert not seen
        *sec, name = new[0].split(".")
        assert _table(data, sec) == {name: 7.0}
        return
    with pytest.warns(ConfigWarning) as seen:
        set_layer(data, [(tuple(new[0].split(".")), 7.0)])
    *sec, name = new[0].split(".")
    assert _table(data, sec) == {name: 7.0}
    notes = [str(w.message) for w in seen]
    assert len(notes) == len(old)
    for k, note in zip(old, notes, strict=True):
        assert note == f"{new[0]}: replaces {k} = 123.0 of the scenario underneath"


def test_a_member_at_its_default_is_cleared_without_a_note():
    data = {"mras": {"R1_rate_per_s": 0.0, "wc_rad_s": 15.0}}  # Scenario.to_dict's form
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        set_layer(data, [(("mras", "R1_rate_pu"), 0.02)])
    assert data == {"mras": {"R1_rate_pu": 0.02, "wc_rad_s": 15.0}}


def test_an_old_absolute_key_runs_on_a_per_unit_preset():
    """The keys of the last release on injection-robust (which states their per-unit twins;
    G_CR_pu no longer: its model-based law has no table step, so G_CR_ohm has no effect and
    says so)."""
    sc, notes = _read(
        "injection-robust",
        "mras.R1_rate_per_s=0.5",
        "estimator.R2_ohm=0.9",
        "compensator.G_CR_ohm=0.01",
        "injection.amplitude_A=0.4",
    )
    assert (sc.mras.R1_rate_per_s, sc.mras.R1_rate_pu) == (0.5, None)
    assert (sc.estimator.R2_ohm, sc.estimator.R2_ratio) == (0.9, None)
    assert (sc.compensator.G_CR_ohm, sc.compensator.G_CR_pu) == (0.01, None)
    assert (sc.injection.amplitude_A, sc.injection.amplitude_pu) == (0.4, None)
    assert sc.estimator.R1_ratio == 1.1  # the rest of the preset is untouched
    assert notes == [
        "mras.R1_rate_per_s: replaces mras.R1_rate_pu = 0.02621 of the scenario underneath",
        "estimator.R2_ohm: replaces estimator.R2_ratio = 1.2 of the scenario underneath",
        "injection.amplitude_A: replaces injection.amplitude_pu = 0.075 of the scenario underneath",
        # deprecated twins since round 7: they act, and say what to state instead
        "compensator.G_CR_ohm: deprecated, refused from imdrive 0.3: state it per-unit of the "
        "machine as compensator.G_CR_pu (it still acts until then)",
        "injection.amplitude_A: deprecated, refused from imdrive 0.3: state it per-unit of the "
        "machine as injection.amplitude_pu (it still acts until then)",
        'compensator.G_CR_ohm: has no effect with step_law = "kalman": the model-based law '
        "reads its settings from [kalman] (noise_pu, drift_pu)",
    ]
    from imdrive.config.perunit import resolve

    r = resolve(sc)
    assert (r.R2_hat, r.G_CR, r.inj_amp) == (0.9, 0.01, 0.4)  # the absolute values are used


def test_a_per_unit_key_replaces_the_absolute_one_of_a_preset():
    sc, notes = _read("injection-fig5", "mras.R1_rate_pu=0.03", "estimator.R2_ratio=0.8")
    assert (sc.mras.R1_rate_per_s, sc.mras.R1_rate_pu) == (0.0, 0.03)
    assert (sc.estimator.R2_ohm, sc.estimator.R2_ratio) == (None, 0.8)
    assert len(notes) == 2 and "replaces mras.R1_rate_per_s = 0.3" in notes[0]


def test_with_overrides_clears_the_other_member():
    base = Scenario.read("injection-robust")
    with pytest.warns(ConfigWarning, match="replaces mras.R1_rate_pu"):
        sc = base.with_overrides({"mras.R1_rate_per_s": 0.0})  # the law off, in the old key
    assert (sc.mras.R1_rate_per_s, sc.mras.R1_rate_pu) == (0.0, None)
    with pytest.warns(ConfigWarning, match="replaces estimator.R2_ratio = 1.2"):
        sc = base.with_overrides(["estimator.R2_ohm=0.9"])
    assert (sc.estimator.R2_ohm, sc.estimator.R2_ratio) == (0.9, None)
    # a member set to None clears only itself
    sc = base.with_overrides({"estimator.R2_ratio": None})
    assert (sc.estimator.R2_ohm, sc.estimator.R2_ratio) == (None, None)


def test_the_injection_frequency_switches_units():
    # (its alternatives frequency2_*, frequency3_* are the harmonics now: no keys of their own)
    sc, notes = _read("injection-robust", "injection.frequency_Hz=2.0")
    assert sc.injection.frequency_pu is None
    assert [n.split(" = ")[0].split(":")[:2] for n in notes] == [
        ["injection.frequency_Hz", " replaces injection.frequency_pu"],
        ["injection.frequency_Hz", " deprecated, refused from imdrive 0.3"],  # since round 7
    ]


# -- both members in one layer ----------------------------------------------------------------


@pytest.mark.parametrize(
    "pair", [p for p in PAIRS if p.both == "error"], ids=lambda p: p.per_unit[0]
)
def test_both_members_in_one_override_list_are_refused_naming_both(pair):
    a, u = pair.absolute[0], pair.per_unit[0]
    data: dict = {}
    with pytest.raises(ConfigError) as exc:
        set_layer(data, [(tuple(a.split(".")), 123.0), (tuple(u.split(".")), 4.5)], "--set")
    assert exc.value.field == u
    assert a in exc.value.rule and u in exc.value.rule and "--set" in exc.value.rule


@pytest.mark.parametrize(
    "section, both",
    [
        ("estimator", "R2_ohm = 0.9\nR2_ratio = 1.2"),
        ("estimator", "M_H = 0.03\nM_ratio = 1.1"),
        ("compensator", "R2_max_ohm = 2.0\nR2_max_ratio = 2.5"),
        ("mras", "R1_rate_per_s = 0.3\nR1_rate_pu = 0.02"),
        ("mras", "R1_max_freq_Hz = 20.0\nR1_max_freq_pu = 0.4"),
    ],
)
def test_both_members_in_one_file_are_refused(tmp_path, section, both):
    path = tmp_path / "both.toml"
    path.write_text(f"[{section}]\n{both}\n")
    a, u = (line.split(" = ")[0] for line in both.splitlines())
    with pytest.raises(ConfigError, match=f"set {section}.{a} or {section}.{u}, not both"):
        Scenario.read(str(path))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2


def test_both_members_on_the_command_line_exit_2(tmp_path, capsys):
    sets = ["--set", "mras.R1_rate_per_s=0.5", "--set", "mras.R1_rate_pu=0.03"]
    rc = main(["run", "injection-robust", *sets, "--out", str(tmp_path), "-q"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "mras.R1_rate_per_s" in err and "mras.R1_rate_pu" in err and "not both" in err


def test_a_replacing_pair_in_one_file_is_deprecated_not_refused(tmp_path):
    """``G_CR_pu`` was documented to replace ``G_CR_ohm``: both in a file still run so."""
    path = tmp_path / "both.toml"
    path.write_text('[drive]\nmode = "vector"\n[compensator]\nG_CR_ohm = 0.01\nG_CR_pu = 0.02\n')
    with pytest.warns(ConfigWarning, match="G_CR_pu is used \\(deprecated: set one of them\\)"):
        sc = Scenario.read(str(path))
    from imdrive.config.perunit import resolve

    assert resolve(sc).G_CR == pytest.approx(0.02 * sc.machine.R2_ohm)


# -- sweeps -----------------------------------------------------------------------------------


def test_a_sweep_over_one_member_runs_on_a_preset_carrying_the_other():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sw = parse_sweep(
            'base = "injection-robust"\n'
            '[axes]\n"mras.R1_rate_per_s" = { values = [0.0, 0.5] }\n'
            '"estimator.R2_ohm" = { values = [0.9] }\n'
        )
        runs = [sw.scenario(k) for k in range(2)]
    assert [(s.mras.R1_rate_per_s, s.mras.R1_rate_pu) for s in runs] == [(0.0, None), (0.5, None)]
    assert all((s.estimator.R2_ohm, s.estimator.R2_ratio) == (0.9, None) for s in runs)


def test_a_sweep_set_table_is_one_layer_on_its_base():
    with pytest.warns(ConfigWarning, match="replaces mras.R1_rate_pu"):
        sw = parse_sweep(
            'base = "injection-robust"\n[set]\n"mras.R1_rate_per_s" = 0.4\n'
            '[axes]\n"control.current_bandwidth_Hz" = { values = [200.0] }\n'
        )
    assert sw.scenario(0).mras.R1_rate_pu is None
    with pytest.raises(ConfigError, match="not both"):
        parse_sweep(
            'base = "injection-fig5"\n[set]\n"estimator.R2_ohm" = 0.9\n'
            '"estimator.R2_ratio" = 1.1\n[axes]\n"control.current_bandwidth_Hz" = '
            "{ values = [200.0] }\n"
        )


def test_two_sweep_axes_over_both_members_are_refused():
    # refused when the axes are read (sweep/axes.py), naming both, before any scenario
    with warnings.catch_warnings(), pytest.raises(ConfigError, match="twins of one quantity"):
        warnings.simplefilter("ignore", ConfigWarning)  # each axis alone on the base is fine
        parse_sweep(
            'base = "injection-fig5"\n[axes]\n"estimator.R2_ohm" = { values = [0.9] }\n'
            '"estimator.R2_ratio" = { values = [1.1] }\n'
        )


def test_defaults_of_the_pairs_state_nothing():
    """Every preset as read states at most one member of each pair (no note, no error), and
    its file form reads back to the same scenario."""
    from imdrive.config.presets import preset_names

    for name in preset_names():
        sc, notes = _read(name)
        assert notes == [], name
        assert Scenario.from_dict(sc.to_dict()) == sc
