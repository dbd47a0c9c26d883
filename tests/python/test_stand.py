"""The default stand has one source, the Rust stand (crates/stewart-core/src/physics/stand.rs),
which writes the FMUs' start values: the package reads it from the platform FMU's model
description (`stewart_fmu.default_stand`, `stand_parameters`), and it equals docs/model.md §3's
stand written out independently (tests/python/oracles/stand.py) to the bit, in SI and in the
paper's units; the controller and the cueing FMU carry the same stand."""

import pytest
from fmpy import read_model_description

import stewart_fmu
from stewart_fmu import CONTROLLER_FMU, PLATFORM_FMU, default_stand, stand_parameters
from stewart_fmu.core import CUEING_FMU
from oracles import stand as oracle

pytestmark = pytest.mark.quick


def start_values(fmu):
    return {v.name: float(v.start) for v in read_model_description(str(fmu)).modelVariables
            if v.type == "Real" and v.start is not None}


@pytest.mark.parametrize("nondimensional", [False, True])
def test_the_packages_stand_is_the_documented_stand_to_the_bit(nondimensional):
    package, documented = stand_parameters(nondimensional), oracle.stand_parameters(nondimensional)
    different = {k: (package.get(k), x) for k, x in documented.items() if package.get(k) != x}
    print(f"stand_parameters(nondimensional={nondimensional}): {len(documented)} values equal docs/model.md §3's "
          f"stand to the bit; different: {different}")
    assert not different
    assert set(package) - set(documented) == ({"stops", "joints"} if nondimensional else set())


def test_the_packages_stand_constants_are_the_fmus():
    stand = default_stand()
    assert (stewart_fmu.MASS, stewart_fmu.INERTIA, stewart_fmu.GRAVITY, stewart_fmu.NEUTRAL_Z) == (
        oracle.MASS, oracle.INERTIA, oracle.GRAVITY, oracle.NEUTRAL_Z)
    assert stand["r0"] == (0.0, 0.0, oracle.NEUTRAL_Z)


def test_the_controller_and_the_cueing_carry_the_platforms_stand():
    platform = start_values(PLATFORM_FMU)
    joints = [f"{m}[{k},{i}]" for m in "BA" for k in range(1, 7) for i in (1, 2, 3)]
    for fmu, names in ((CONTROLLER_FMU, ["M", "J[1]", "J[2]", "J[3]", "g"] + joints),
                       (CUEING_FMU, joints + [f"{n}[{k}]" for n in ("lmin", "lmax") for k in range(1, 7)])):
        other = start_values(fmu)
        different = [n for n in names if other[n] != platform[n]]
        print(f"{fmu.name}: {len(names)} stand values equal the platform's; different: {different}")
        assert not different
