"""The SSP systems the package ships (StewartSystem.ssp: the closed loop on leg forces;
StewartSystemDrives.ssp: on the drives' voltages, `drive = 1`; StewartSystemHydraulic.ssp: on
the servo valves' commands with the chamber pressures measured, `drive = 2`;
StewartMotionSystem.ssp: motion cueing ahead of the closed loop) and the reading of their
system structure, for the Python master (`stewart_fmu.cosim`), the compiled one
(`stewart_fmu.master`) and the studies (`stewart_fmu.study`)."""

import re
import zipfile
from pathlib import Path

from .core import PLATFORM_FMU, fmu_file

SYSTEM_SSP = Path(PLATFORM_FMU).parent / "StewartSystem.ssp"
# The closed loop with electric drives (docs/model.md §9): parameter bindings set drive = 1.
SYSTEM_DRIVES_SSP = Path(PLATFORM_FMU).parent / "StewartSystemDrives.ssp"
# The closed loop with hydraulic servo legs (docs/model.md §10): parameter bindings set drive = 2.
SYSTEM_HYDRAULIC_SSP = Path(PLATFORM_FMU).parent / "StewartSystemHydraulic.ssp"
# The same fed by the power unit (docs/model.md §10b): hydraulic.supply = 1, the controller's
# safe landing below landing.pressure = 12 MPa; the platform's pump.speed left to the host.
SYSTEM_POWER_UNIT_SSP = Path(PLATFORM_FMU).parent / "StewartSystemPowerUnit.ssp"
# The whole motion system (docs/cueing.md): vehicle -> StewartCueing -> StewartController
# (programme = 3, a parameter binding) -> StewartPlatform.
MOTION_SYSTEM_SSP = Path(PLATFORM_FMU).parent / "StewartMotionSystem.ssp"
#: The shipped system of each `drive`.
SYSTEMS = {0: SYSTEM_SSP, 1: SYSTEM_DRIVES_SSP, 2: SYSTEM_HYDRAULIC_SSP}


def system_description(ssp, bindings=True):
    """The text of an SSP file's SystemStructure.ssd (`bindings=False`: without its parameter
    bindings, for a master that sets every value itself, as the studies and
    `stewart_fmu.cosim.closed_loop` do)."""
    with zipfile.ZipFile(ssp) as z:
        text = z.read("SystemStructure.ssd").decode()
    return text if bindings else re.sub(r"<ssd:ParameterBindings>.*?</ssd:ParameterBindings>", "", text, flags=re.S)


def couplings():
    """The closed loop's couplings the compiled master runs, by `drive`: the package's
    StewartSystem.ssd (forces), StewartSystemDrives.ssd (voltages) and StewartSystemHydraulic.ssd
    (valve commands), without bindings."""
    return {drive: system_description(fmu_file(ssp), drive == 0) for drive, ssp in SYSTEMS.items()}


def connections(ssd):
    """The connections of an SSD text: (start element, start connector, end element, end
    connector) in the file's order."""
    pattern = (r'<ssd:Connection startElement="([^"]+)" startConnector="([^"]+)" endElement="([^"]+)" '
               r'endConnector="([^"]+)"/>')
    return re.findall(pattern, ssd)


def bindings(ssd):
    """The inline parameter bindings of an SSD text: {component: {parameter: value}} (Real
    values as floats, Integer ones as ints, Boolean ones as bools)."""
    out = {}
    for name, body in re.findall(r'<ssd:Component name="([^"]+)".*?>(.*?)</ssd:Component>', ssd, flags=re.S):
        for parameter, kind, value in re.findall(
                r'<ssv:Parameter name="([^"]+)"><ssv:(Real|Integer|Boolean) value="([^"]+)"/>', body):
            convert = {"Real": float, "Integer": int, "Boolean": lambda v: v == "true"}[kind]
            out.setdefault(name, {})[parameter] = convert(value)
    return out
