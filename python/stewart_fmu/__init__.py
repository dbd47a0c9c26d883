"""Python tooling for the Stewart platform FMUs: drive them with FMPy, couple the platform and
the controller, run the workspace scenarios, linearise, and run design studies on Dask
(`stewart-sweep`). Install into the repository's environment with `pip install -e python`
(both README commands do), or from the wheel `python/build_wheel.sh` builds, which carries the
FMUs and the viewer page."""

from .core import (BASE_AZIMUTHS, CONTROLLER_FMU, EQUILIBRIUM_FORCE, GRAVITY, H_C, INERTIA, MASS, NEUTRAL_Z,
                   PLATFORM_AZIMUTHS, PLATFORM_FMU, R_B, R_P, ROOT, Component, Platform, bisect_boundary, heave_forces,
                   heave_programme, neutral_leg_geometry, recording_callbacks, set_values, stand_parameters)

__all__ = ["BASE_AZIMUTHS", "CONTROLLER_FMU", "EQUILIBRIUM_FORCE", "GRAVITY", "H_C", "INERTIA", "MASS", "NEUTRAL_Z",
           "PLATFORM_AZIMUTHS", "PLATFORM_FMU", "R_B", "R_P", "ROOT", "Component", "Platform", "bisect_boundary",
           "heave_forces", "heave_programme", "neutral_leg_geometry", "recording_callbacks", "set_values",
           "stand_parameters"]
