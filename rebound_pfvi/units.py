"""Units at the public boundary; the core and the scenes' numbers stay unitless.

Every scene runs in one unit system, REBOUND's ``sim.units = ("AU", "yr",
"Msun")``. Its G is the only G in rebound_pfvi: REBOUND computes it
(39.476926421 AU^3 / (Msun yr^2): Gauss's constant k = 0.01720209895 squared,
per day^2, times 365.25^2; the IAU 2015 nominal GM_sun gives 39.476926409,
3e-10 less) and nothing here takes G from astropy. astropy only converts user Quantities into AU, yr and Msun and back
(``.to_value(unit)`` in, ``<< unit`` out), so ratios of masses given in Msun,
Mjup or Mearth carry the nominal GM ratios and no G at all. A mass given in kg
goes through astropy's M_sun, which is GM_sun / G(CODATA 2018); REBOUND's own
G_SI is CODATA 2014 (6.67408e-11 against 6.67430e-11): that is why nothing
here builds a simulation in SI units.

astropy is imported on first use, so that ``import rebound_pfvi`` and the
integrator never need it.
"""
from __future__ import annotations

import math
import re
from typing import Any, Optional

#: The unit system of every scene, as REBOUND's ``sim.units`` names it.
REBOUND_UNITS = ("AU", "yr", "Msun")
#: The same units, as astropy names them; a value's dimension picks one.
_ASTROPY_NAMES = {"length": "AU", "time": "yr", "mass": "solMass"}
#: Units with which a dimension may be given on the command line or in Python.
ALLOWED = {
    "length": ("AU", "km", "m", "pc", "Rsun", "Rjup", "Rearth"),
    "time": ("yr", "day", "d", "s", "h"),
    "mass": ("Msun", "Mjup", "Mearth", "kg"),
    "frequency": ("1/yr", "1/day", "1/s", "rad/yr", "rad/day", "rad/s"),
}


def _u() -> Any:
    import astropy.units as u

    return u


def scene_unit(kind: str) -> Any:
    """The astropy unit of a scene's numbers of one kind: length, time, mass,
    frequency (1/yr), speed (AU/yr) or energy per mass (AU^2/yr^2)."""
    u = _u()
    if kind in _ASTROPY_NAMES:
        return u.Unit(_ASTROPY_NAMES[kind])
    derived = {"frequency": u.yr**-1, "speed": u.AU / u.yr, "specific_energy": (u.AU / u.yr)**2}
    if kind not in derived:
        raise ValueError(f"kind={kind!r} is not a unit kind; allowed: "
                         f"{', '.join(list(_ASTROPY_NAMES) + list(derived))}")
    return derived[kind]


def parse(text: str, kind: str, name: str) -> Any:
    """A Quantity from a string such as "1 AU" or "0.3 Mjup" (the command line).

    `name` is the argument's name, used in the error when the text is not a
    number with a unit of the right kind."""
    u = _u()
    # (the kinds with no list of their own, speed and energy per mass, in the scene's unit)
    allowed = ALLOWED.get(kind) or (scene_unit(kind).to_string(),)
    try:
        value = u.Quantity(text)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: cannot read {text!r} as a quantity ({_unit_error(error)}); "
                         f"write a number and a unit, e.g. \"1 {allowed[0]}\" "
                         f"(units: {', '.join(allowed)})") from None
    if value.unit == u.dimensionless_unscaled:
        raise ValueError(f"{name}: {text!r} has no unit; write a number and a unit, e.g. "
                         f"\"{text.strip()} {allowed[0]}\" (units: {', '.join(allowed)})")
    # The text as the user wrote it, for errors about the value (show());
    # astropy keeps it on this Quantity only, not on what is computed from it.
    value.info.description = " ".join(text.split())
    to_unit(value, kind, scene_unit(kind), name)  # of the kind asked for ("1 AU" is no time), finite
    return value


def _unit_error(error: Exception) -> str:
    """astropy's complaint about a unit, without its advice on defining
    custom units: "parsecs is not a valid unit. Did you mean parsec?"."""
    message = str(error).split(" If this is meant to be a custom unit")[0]
    message = re.sub(r"^'[^']*' did not parse as unit: (At col \d+, )?", "", message)
    return message.strip()


def show(value: Any) -> str:
    """A value for an error message: a Quantity read by :func:`parse` as the
    user wrote it ("-1 Mjup"), another as astropy writes it ("-1 jupiterMass"),
    anything else as its repr."""
    written = getattr(getattr(value, "info", None), "description", None)
    if isinstance(written, str) and written:
        return written
    if hasattr(value, "unit") and hasattr(value, "value"):
        return f"{value.value:g} {value.unit}" if value.isscalar else str(value)
    return repr(value)


def to_scene(value: Any, kind: str, name: str) -> float:
    """A float in the scene's unit of `kind` from a Quantity, or a plain number
    taken to be in that unit already. `name` names the argument in errors."""
    if isinstance(value, str):
        value = parse(value, kind, name)
    if hasattr(value, "unit"):
        return to_unit(value, kind, scene_unit(kind), name)
    return plain_number(value, name)


def to_unit(value: Any, kind: str, unit: Any, name: str) -> float:
    """A Quantity of `kind` (length, time, mass, frequency) as a finite float
    in `unit` (an astropy unit or its name). `name` names the argument in
    errors, which name the kind a Quantity of another kind is not."""
    u = _u()
    if not getattr(value, "isscalar", True):
        raise ValueError(f"{name}={show(value)} is not a single value; give one quantity")
    if kind == "frequency" and any("Hz" in getattr(base, "name", "") for base in getattr(value.unit, "bases", ())):
        # astropy's Hz is 1/s, so that "1 Hz" would become 1 rad/s where a
        # cycle a second (2 pi rad/s) is almost always meant.
        raise ValueError(f"{name}={show(value)}: hertz is ambiguous for an angular frequency (astropy reads 1 Hz "
                         f"as 1 rad/s, not one cycle a second); give rad/s, cycle/s or 1/s "
                         f"(allowed: {', '.join(ALLOWED['frequency'])}, cycle/...)")
    try:
        # Frequencies may be given in rad/time; radians are dimensionless
        # there (and nowhere else: "1 AU rad" is no length).
        number = value.to_value(unit, equivalencies=u.dimensionless_angles() if kind == "frequency" else [])
    except u.UnitConversionError:
        raise ValueError(f"{name}={show(value)} has unit {value.unit}, which is not a {kind}; "
                         f"allowed: {', '.join(ALLOWED.get(kind, (str(unit),)))}") from None
    number = float(number)
    if not math.isfinite(number):
        raise ValueError(f"{name}={show(value)} is not finite")
    return number


def plain_number(value: Any, name: str) -> float:
    """A finite float from a number (not a bool); errors name the argument."""
    if isinstance(value, bool):
        raise ValueError(f"{name}={value!r} is not a number")
    try:
        number = float(value)
    except (TypeError, ValueError):
        if isinstance(value, str):  # (the command line's text)
            raise ValueError(f"{name}={value!r} is not a number") from None
        if hasattr(value, "unit"):   # (a dimensionless Quantity converts above)
            raise ValueError(f"{name}={value!r} has unit {value.unit}; {name} takes a plain number") from None
        raise ValueError(f"{name}={value!r} is neither a number nor a Quantity") from None
    if not math.isfinite(number):
        raise ValueError(f"{name}={value!r} is not finite")
    return number


def to_quantity(number: float, kind: str, unit: Optional[Any] = None) -> Any:
    """A scene number as a Quantity, in the scene unit or converted to `unit`."""
    q = number * scene_unit(kind)
    return q if unit is None else q.to(unit)
