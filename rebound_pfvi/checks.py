"""The checks of arguments that both the command line and the Python API make.

Each check takes the value and the name of the argument, and returns the
value as it is used or raises ValueError naming the argument and the value
("repeats=2.5 is not an integer"). The Python functions call them with
their own argument names (compare.run, stability.run_all, demo.run_demo,
report.write); the command line calls the same checks through argparse, with
the option's name in place of the argument's (rebound_pfvi.__main__), so
that each rule is written once. Quantities are checked by
:mod:`rebound_pfvi.units`; nothing here imports astropy.
"""
from __future__ import annotations

import numbers
import os
from typing import Any, Iterable, List

from . import units


def positive_int(value: Any, name: str) -> int:
    """An integer >= 1 from an int or its text ("3"); 2.5, "2.5", True and a Quantity are refused."""
    if isinstance(value, str):
        try:
            number = int(value)
        except ValueError:
            raise ValueError(f"{name}={value!r} is not an integer") from None
    elif isinstance(value, numbers.Integral) and not isinstance(value, bool):
        number = int(value)
    else:
        raise ValueError(f"{name}={value!r} is not an integer")
    if number < 1:
        raise ValueError(f"{name}={number} must be at least 1")
    return number


def positive_number(value: Any, name: str) -> float:
    """A finite float > 0 from a number or its text ("1e-6")."""
    number = units.plain_number(value, name)
    if not number > 0.0:
        raise ValueError(f"{name}={value!r} must be positive")
    return number


def seconds(value: Any, name: str) -> float:
    """A positive number of seconds from a number (in seconds) or a time
    Quantity (``5 * u.s``, ``2 * u.min``); a Quantity of another kind is
    refused naming the kind it is not."""
    if hasattr(value, "unit"):
        number = units.to_unit(value, "time", "s", name)
        if not number > 0.0:
            raise ValueError(f"{name}={units.show(value)} must be positive")
        return number
    return positive_number(value, name)


def names(values: Iterable[str], allowed: Iterable[str], name: str, what: str) -> List[str]:
    """`values` as a list, each one of `allowed` and each once: a name not
    allowed, or one given twice, is refused naming it (`what` says what a name
    is: "a case"), as is an empty list."""
    allowed, values = list(allowed), list(values)
    bad = [v for v in values if v not in allowed]
    if bad or not values:
        raise ValueError(f"{name}: {', '.join(map(str, bad)) + ' not ' + what if bad else 'none given'}; "
                         f"allowed: {', '.join(allowed)}")
    twice = list(dict.fromkeys(v for i, v in enumerate(values) if v in values[:i]))
    if twice:
        raise ValueError(f"{name}: {', '.join(twice)} given twice; give each once")
    return values


def file_name(value: Any, name: str) -> str:
    """A file's name without a folder: no path separator, not "", "." or ".."
    (a name that would write outside the folder it is meant for)."""
    if not isinstance(value, str):
        raise ValueError(f"{name}={value!r} is not a file name (a string)")
    separators = sorted({"/", os.sep, os.altsep or "/"})
    if value in ("", ".", "..") or any(s in value for s in separators) or "\0" in value:
        raise ValueError(f"{name}={value!r} is not a file name: give a name without a folder (no "
                         f"{' or '.join(map(repr, separators))}, not '..'); the folder is the output's")
    return value
