"""Python tooling for the Stewart platform FMUs: drive them with FMPy, couple the platform and
the controller, run the workspace scenarios, linearise, and run design studies on Dask
(`stewart-sweep`). Install into the repository's environment with `pip install -e python`
(both README commands do), or from a wheel `bash python/build_wheels.sh` builds (Linux x86-64 and
aarch64, Windows x64), which carries the FMUs, the viewer page and the compiled master."""

from . import core
from .core import (CONTROLLER_FMU, EQUILIBRIUM_FORCE, PLATFORM_FMU, ROOT, Component, Platform, bisect_boundary,
                   default_stand, recording_callbacks, set_values, stand_parameters)

__all__ = ["CONTROLLER_FMU", "EQUILIBRIUM_FORCE", "GRAVITY", "INERTIA", "MASS", "NEUTRAL_Z", "PLATFORM_FMU", "ROOT",
           "Component", "Platform", "bisect_boundary", "default_stand", "recording_callbacks", "set_values",
           "stand_parameters"]


def __getattr__(name):
    """The default stand's `MASS`, `INERTIA`, `GRAVITY` and `NEUTRAL_Z`, read from the platform
    FMU's model description on first use (`stewart_fmu.core.default_stand`)."""
    if name in ("MASS", "INERTIA", "GRAVITY", "NEUTRAL_Z"):
        return getattr(core, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
