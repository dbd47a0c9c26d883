"""Python tooling for the Stewart platform FMUs: drive them with FMPy, couple the platform and
the controller, run the workspace scenarios, linearise, and run design studies on Dask
(`stewart-sweep`). Install into the repository's environment with `pip install -e python`
(both README commands do), or from a wheel `bash python/build_wheels.sh` builds (Linux x86-64 and
aarch64, Windows x64), which carries the FMUs, the viewer page and the compiled master."""

from .core import (BASE_AZIMUTHS, CONTROLLER_FMU, EQUILIBRIUM_FORCE, GRAVITY, H_C, INERTIA, MASS, NEUTRAL_Z,
                   PLATFORM_AZIMUTHS, PLATFORM_FMU, R_B, R_P, ROOT, Component, Platform, bisect_boundary, heave_forces,
                   heave_programme, neutral_leg_geometry, recording_callbacks, set_values, stand_parameters)

__all__ = ["BASE_AZIMUTHS", "CONTROLLER_FMU", "EQUILIBRIUM_FORCE", "GRAVITY", "H_C", "INERTIA", "MASS", "NEUTRAL_Z",
           "PLATFORM_AZIMUTHS", "PLATFORM_FMU", "R_B", "R_P", "ROOT", "Component", "Platform", "bisect_boundary",
           "heave_forces", "heave_programme", "neutral_leg_geometry", "recording_callbacks", "set_values",
           "stand_parameters"]
