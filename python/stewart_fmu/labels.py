"""Axis labels for the studies' plots: a quantity's name and unit, from the FMUs' model
descriptions for parameters (`platform.M` -> "Mass of the loaded platform (M), kg") and from
METRICS for the rows' metrics; in a non-dimensional study the unit is the paper's scale
("non-dimensional, units of R_b")."""

import re

# The rows' metrics (stewart_fmu.study): what each is, its SI unit.
METRICS = {
    "max_leg_error": ("Largest leg-length error |l - l^p|", "m"),
    "max_pose_error": ("Largest position error |r - r^p|", "m"),
    "min_kappa": ("Smallest condition number kappa of the legs", ""),
    "max_stop_force": ("Largest end-stop force |Fstop|", "N"),
    "energy_residual": ("Largest energy-balance residual", "J"),
    "peak_deceleration": ("Peak upward acceleration (largest dv_z/dt over a step)", "m/s2"),
    "final_z": ("Final height of the centre of mass z", "m"),
    "min_supply_pressure": ("Lowest supply pressure p_S the valves see (gauge)", "Pa"),
    "landing_deceleration": ("Peak upward acceleration after the scenario's event (largest dv_z/dt over a step)",
                             "m/s2"),
    "discard_time": ("Time of the discarded step", "s"),
    "wall_time": ("Wall time of the run", "s"),
    "step": ("Communication step", "s"),
    "stop_time": ("End of the run", "s"),
    "scenario.power_loss_at": ("Time of the power loss", "s"),
    "scenario.failure_time": ("Time of the actuator failure", "s"),
    "scenario.failed_leg": ("Failed leg", ""),
    "scenario.pump_stop_at": ("Time the pump stops", "s"),
    "platform.com_offset[1]": ("Centre-of-mass offset along e1", "m"),
    "platform.com_offset[2]": ("Centre-of-mass offset along e2", "m"),
    "platform.com_offset[3]": ("Centre-of-mass offset along e3", "m"),
}

# SI units in the paper's non-dimensional units (docs/model.md §2): length R_b, mass M, force
# M g, time sqrt(R_b/g).
NONDIMENSIONAL = {
    "m": "R_b", "s": "sqrt(R_b/g)", "kg": "M", "N": "M g", "m/s": "sqrt(g R_b)", "m/s2": "g", "N/m": "M g/R_b",
    "N.s/m": "M sqrt(g/R_b)", "J": "M g R_b", "kg.m2": "M R_b^2", "1/s": "sqrt(g/R_b)", "rad/s": "sqrt(g/R_b)",
    "W": "M g sqrt(g R_b)", "Pa": "M g/R_b^2",
}
UNIT_TEXT = {"m/s2": "m/s²", "kg.m2": "kg m²", "N.s/m": "N s/m"}


def short_description(description, index=None):
    """The description's first clause; for an array element whose
    description ends in a list of the elements ("amplitudes of x, y, z"), that element."""
    text = re.sub(r"^Programme \d+( \([^)]*\))?: ", "", description or "").strip()
    text = re.split(r" \(|; |: |\. |, or |, by |, held ", text)[0].rstrip(".")
    items = re.search(r"((?:[\w^]+, )+(?:and )?[\w^]+)$", text)
    if index is not None and items:
        names = [n.replace("and ", "") for n in items.group(1).split(", ")]
        if len(names) >= index:
            head = re.sub(r"^(\w+)s\b", r"\1", text[: items.start()])  # "amplitudes of" -> "amplitude of"
            text = head + names[index - 1]
    if len(text) > 56:
        text = text[:54].rsplit(" ", 1)[0] + " ..."
    return text[:1].upper() + text[1:]


def unit_text(unit, nondimensional):
    if nondimensional:
        if unit == "rad":
            return "rad"
        if unit in ("", None, "1"):
            return "non-dimensional"
        return f"non-dimensional, units of {NONDIMENSIONAL.get(unit, unit)}"
    return UNIT_TEXT.get(unit, unit) if unit else ""


def label(name, variables, nondimensional=False):
    """The axis label of a study parameter or metric `name`; `variables`: {'platform': {name:
    Variable}, 'controller': ...} (study_params.fmu_variables)."""
    if name in METRICS:
        what, unit = METRICS[name]
        symbol = ""
    else:
        role, _, variable = name.partition(".")
        v = (variables or {}).get(role, {}).get(variable)
        if v is None:
            return name
        index = re.search(r"\[(\d+)\]$", variable)
        what = short_description(v.description, int(index.group(1)) if index else None) or variable
        unit, symbol = v.unit or "", f" ({variable})"
    units = unit_text(unit, nondimensional)
    return f"{what}{symbol}" + (f", {units}" if units else "")


def facet_title(name, value, variables, nondimensional=False):
    """A panel's title: the parameter's symbol and value with its unit ("G = 2 N/m")."""
    role, _, variable = name.partition(".")
    v = (variables or {}).get(role, {}).get(variable)
    unit = METRICS[name][1] if name in METRICS else (v.unit if v is not None and v.unit else "")
    shown = "" if nondimensional and unit != "rad" else UNIT_TEXT.get(unit, unit)
    return f"{variable or name} = {value:g}" + (f" {shown}" if shown else "")
