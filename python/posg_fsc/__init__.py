"""posg_fsc: finite-state controllers for partially observable stochastic
games (POSGs) under LTL objectives: exact values, adjoint gradients, max-min
optimisation against a worst-case adversary, and certified bounds.

The classes and functions come from the compiled module `posg_fsc._native`
(the Rust library through pyo3); `__init__.pyi` has their types.
"""

from ._native import *  # noqa: F401,F403 (the public API, documented in __init__.pyi)
from ._native import __version__  # noqa: F401
