"""``imdrive machine-from-nameplate``: estimate (:mod:`imdrive.analysis.nameplate`), check and
write the machine as a TOML file for ``[machine] file = "..."``."""

from __future__ import annotations

import sys
import warnings

from imdrive.analysis.nameplate import LEAKAGE_SPLIT, Nameplate, NameplateFit, estimate_circuit
from imdrive.errors import ConfigError, ConfigWarning

__all__ = ["machine_from_nameplate_command", "machine_toml"]

#: Nameplate field -> the command line's flag (errors name the flag)
FLAGS = {
    "power_W": "--power-kw",
    "voltage_V": "--voltage",
    "frequency_Hz": "--frequency",
    "poles": "--poles",
    "speed_rpm": "--speed",
    "current_A": "--current",
    "power_factor": "--pf",
    "efficiency": "--efficiency",
    "breakdown_torque_ratio": "--breakdown-ratio",
    "starting_current_ratio": "--starting-current-ratio",
    "J_kgm2": "--J",
    "code_letter": "--code-letter",
    "core_loss_fraction": "--core-loss-fraction",
    "mechanical_loss_fraction": "--mechanical-loss-fraction",
    "stray_loss_fraction": "--stray-loss-fraction",
    "locked_rotor_current": "--code-letter / --starting-current-ratio",
    "starting_current": "--starting-current-ratio (or --code-letter)",
}

_METHOD_NOTES = {
    "catalogue": (
        "single-cage T-circuit from every catalogue figure (imdrive.analysis.nameplate, "
        "method catalogue): losses split after Lee, Frank, Sen et al. (NAPS 2012) so that R1 "
        "is the stator's, the leakage from the breakdown torque when given, else from the "
        "starting current or code letter; the plant has no iron, friction or stray loss"
    ),
    "fit": (
        "single-cage T-circuit fitted to the rated point and breakdown torque "
        "(imdrive.analysis.nameplate, method fit; Pedra & Corcoles 2004, Haque 2008); R1 lumps "
        "every loss but the rotor's"
    ),
    "lee": (
        "single-cage T-circuit by the nameplate-only iterative method of Lee, Frank, Sen et al., "
        "NAPS 2012 (imdrive.analysis.nameplate, method lee); its core-loss resistance "
        "is dropped (the plant has no iron-loss branch)"
    ),
}


def machine_toml(fit: NameplateFit, plate: Nameplate) -> str:
    """The estimated machine as a TOML file for ``[machine] file = "..."``.

    Parameters
    ----------
    fit : NameplateFit
        The result of :func:`~imdrive.analysis.nameplate.estimate_circuit`.
    plate : Nameplate
        The data it came from (written into ``source``).

    Returns
    -------
    str
        A ``[machine]`` table with every MachineParams field, ``source`` and ``notes``.
    """
    from imdrive.config.toml_writer import dumps

    data_text = (
        f"{plate.power_W:g} W, {plate.voltage_V:g} V, {plate.frequency_Hz:g} Hz, "
        f"{plate.poles} poles, {plate.speed_rpm:g} rpm, {plate.current_A:g} A, "
        f"cos phi {plate.power_factor:g}, eta {plate.efficiency:g}"
    )
    if plate.breakdown_torque_ratio is not None:
        data_text += f", T_bd/T_n {plate.breakdown_torque_ratio:g}"
    if plate.starting_current_ratio is not None:
        data_text += f", I_st/I_n {plate.starting_current_ratio:g}"
    if plate.code_letter is not None:
        data_text += f", code letter {plate.code_letter}"
    residuals = ", ".join(f"{k} {v:+.1e}" for k, v in fit.residuals.items())
    values = {k: v for k, v in fit.machine.to_dict().items() if v is not None and k != "file"}
    table = {
        "source": f"imdrive machine-from-nameplate from {data_text}",
        "notes": (
            _METHOD_NOTES[fit.method]
            + "; "
            + (f"assumed: {'; '.join(fit.assumed)}; " if fit.assumed else "")
            + f"relative residuals: {residuals}"
        ),
        **values,
    }
    return (
        "# An induction machine estimated from its nameplate by imdrive machine-from-nameplate.\n"
        '# Use it in a scenario: [machine] file = "THIS_FILE.toml"\n' + dumps({"machine": table})
    )


def _method(args) -> str:
    """``--method``, by default ``catalogue``; ``lee`` and ``fit`` warn that they are
    deprecated."""
    method = getattr(args, "method", None) or "catalogue"
    if method == "lee" and args.breakdown_ratio is not None:
        raise ConfigError(
            "--breakdown-ratio",
            "method lee does not use a breakdown ratio: use --method catalogue (the default)",
        )
    if method != "catalogue":
        what = {"lee": "takes no breakdown torque", "fit": "puts every loss into R1"}[method]
        warnings.warn(
            ConfigWarning(
                "--method",
                f"{method} is deprecated ({what}): use --method catalogue (the default), "
                "which uses every catalogue figure and keeps R1 the stator's",
            ),
            stacklevel=2,
        )
    return method


def _lee_options(args) -> dict:
    names = ("core_loss_fraction", "mechanical_loss_fraction", "stray_loss_fraction")
    return {k: getattr(args, k) for k in names if getattr(args, k, None) is not None}


def machine_from_nameplate_command(args) -> int:
    """``imdrive machine-from-nameplate``: estimate, check, write the TOML (or print it).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (``power_kW``, ``voltage``, ``frequency``, ``poles``,
        ``speed``, ``current``, ``pf``, ``efficiency``, ``breakdown_ratio``,
        ``starting_current_ratio``, ``code_letter``, ``design``, ``J``, ``method``, the loss
        fractions, ``description``, ``out``).

    Returns
    -------
    int
        0 (errors are raised as :class:`~imdrive.errors.ConfigError`).
    """
    out = None
    if args.out is not None:  # checked before any work: a device, FIFO or folder is refused
        from imdrive._io import file_path_problem, real_file

        problem = file_path_problem(args.out)
        if problem is not None:
            raise ConfigError("--out", problem)
        out = real_file(args.out)  # a symbolic link stays one: its target is written
    method = _method(args)
    options = _lee_options(args)
    if method == "fit" and options:
        raise ConfigError(
            FLAGS[next(iter(options))], "only methods catalogue and lee take loss fractions"
        )
    try:
        plate = _plate_from_args(args)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fit = estimate_circuit(plate, args.description or "", method, **options)
    except ConfigError as exc:
        raise ConfigError(_flags(exc.field), exc.rule) from None
    for w in caught:  # a nameplate field's warning names its flag; DeprecationWarning: above
        if isinstance(w.message, ConfigWarning):
            warnings.warn(ConfigWarning(_flags(w.message.field), w.message.rule), stacklevel=2)
    text = machine_toml(fit, plate)
    print(f"imdrive: note: method {method}", file=sys.stderr)
    for what in fit.assumed:
        print(f"imdrive: note: assumed {what}", file=sys.stderr)
    _notes(fit)
    if out is not None:
        from imdrive._io import output_file

        # the same check again (the path may have changed during the estimate), then a
        # temporary file renamed in the target's folder
        with output_file(args.out, lambda problem: ConfigError("--out", problem)) as tmp:
            tmp.write_text(text, encoding="utf-8")
        print(f"imdrive: wrote {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _flags(fields: str) -> str:
    """The flags of a comma-separated list of Nameplate fields (others kept as they are)."""
    return ", ".join(FLAGS.get(f, f) for f in fields.split(", "))


def _notes(fit: NameplateFit) -> None:
    """One line on stderr for each way the estimate misses the data."""
    r = fit.residuals
    if fit.method == "catalogue":
        d = fit.details
        print(
            f"imdrive: note: leakage from the {d['leakage_from']}; the circuit's breakdown "
            f"torque {d['breakdown_torque_Nm']:.4g} N m and starting current "
            f"{d['starting_current_A']:.4g} A at rated voltage",
            file=sys.stderr,
        )
        if "starting_current" in r:
            print(
                f"imdrive: note: its starting current is {100 * r['starting_current']:+.1f} % "
                "off the catalogue's (a deep-bar or double-cage rotor starts with less "
                "leakage than it runs with: the breakdown torque sets the running leakage)",
                file=sys.stderr,
            )
    if fit.method in ("catalogue", "lee"):
        print(
            f"imdrive: note: at rated speed the circuit gives {100 * r['rated_torque']:+.1f} % "
            f"torque and {100 * r['rated_current']:+.1f} % current against the nameplate (the "
            "plant has no iron-loss branch, no friction and no stray loss)",
            file=sys.stderr,
        )
        return
    eta_error = r["efficiency"]
    if abs(eta_error) > 0.02:
        print(
            f"imdrive: note: sqrt(3) V I cos phi eta is {100 * eta_error:+.1f} % off the rated "
            "power: the circuit meets power, speed, current and power factor, its efficiency "
            "is P / (sqrt(3) V I cos phi)",
            file=sys.stderr,
        )
    worst = max(abs(v) for k, v in r.items() if k != "efficiency")
    if worst > 1e-3:
        print(
            f"imdrive: note: no single-cage circuit meets all the data (largest relative "
            f"residual {worst:.2g}); the least-squares compromise is written",
            file=sys.stderr,
        )


def _plate_from_args(args) -> Nameplate:
    return Nameplate(
        power_W=args.power_kW * 1e3,
        voltage_V=args.voltage,
        frequency_Hz=args.frequency,
        poles=args.poles,
        speed_rpm=args.speed,
        current_A=args.current,
        power_factor=args.pf,
        efficiency=args.efficiency,
        breakdown_torque_ratio=args.breakdown_ratio,
        starting_current_ratio=args.starting_current_ratio,
        leakage_split=LEAKAGE_SPLIT[args.design],
        J_kgm2=args.J,
        code_letter=getattr(args, "code_letter", None),
    )
