"""Independent formulations the tests (and the main job's demonstrations, which compare the
FMUs with them) check the FMUs against: each written from docs/model.md alone, never from the
Rust code, and kept out of the shipped package (python/stewart_fmu), which takes what it needs
from the FMUs themselves.

- `stand`: docs/model.md §3's default stand (radii, azimuths, mass, inertia, neutral height) and
  its parameter set in SI or the paper's units;
- `heave`: the paper's heave programme (5.1) and its direct problem for the symmetric stand;
- `drives`: §9's electric drive, its static model, dynamic braking and the braked descent;
- `hydraulics`: §10's cylinders, valves and leakage: areas, flow coefficient, chamber volumes,
  holding pressures and the locked legs' creep.

The tests import them as `oracles.NAME` (pytest puts tests/python on the path); the
demonstrations in examples/ put tests/python on their path first.
"""
