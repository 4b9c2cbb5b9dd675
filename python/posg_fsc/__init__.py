"""posg_fsc: finite-state controllers for partially observable stochastic
games (POSGs) under LTL objectives: exact values, adjoint gradients, max-min
optimisation against a worst-case adversary, and certified bounds.

The classes and functions come from the compiled module `posg_fsc._native`
(the Rust library through pyo3); `__init__.pyi` has their types.
"""

import functools as _functools
import textwrap as _textwrap

from . import _native
from ._native import *  # noqa: F401,F403 (the public API, documented in __init__.pyi)
from ._native import __version__  # noqa: F401


def _settings_table():
    """Every setting of solve and sweep: keyword, default and meaning, as
    help() shows them (the text of the command line's --help)."""
    lines = ["", "Settings (keyword=default: meaning):", ""]
    for setting in _native.settings():
        head = f"{setting['keyword']}={setting['default']!r}"
        lines.append(_textwrap.fill(
            f"{head}: {setting['meaning']}", width=79, initial_indent="    ",
            subsequent_indent="        ",
        ))
    return "\n".join(lines)


def _with_settings(function):
    """`function` with the settings table after its documentation."""

    @_functools.wraps(function)
    def documented(*args, **kwargs):
        return function(*args, **kwargs)

    documented.__doc__ = (function.__doc__ or "") + "\n" + _settings_table()
    return documented


solve = _with_settings(_native.solve)
sweep = _with_settings(_native.sweep)
