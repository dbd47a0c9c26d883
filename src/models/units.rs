//! The units the models use, with their SI base-unit exponents
//! `(kg, m, s, A, K, mol, cd, rad)` for `<UnitDefinitions>`.

use super::variables::UnitDefinition;

const DEG_PER_RAD: f64 = 57.29577951308232;

pub static UNITS: &[UnitDefinition] = &[
    UnitDefinition { name: "1", base: [0, 0, 0, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "s", base: [0, 0, 1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "1/s", base: [0, 0, -1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "1/s2", base: [0, 0, -2, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m", base: [0, 1, 0, 0, 0, 0, 0, 0], display_units: &[("mm", 1000.0)] },
    UnitDefinition { name: "m/s", base: [0, 1, -1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m/s2", base: [0, 1, -2, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m/s3", base: [0, 1, -3, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m/s4", base: [0, 1, -4, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m.s", base: [0, 1, 1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "kg", base: [1, 0, 0, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "kg.m2", base: [1, 2, 0, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "N", base: [1, 1, -2, 0, 0, 0, 0, 0], display_units: &[("kN", 1e-3)] },
    UnitDefinition { name: "N/m", base: [1, 0, -2, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "N.s/m", base: [1, 0, -1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "J", base: [1, 2, -2, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "W", base: [1, 2, -3, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "N.m/rad", base: [1, 2, -2, 0, 0, 0, 0, -1], display_units: &[] },
    UnitDefinition { name: "N.m.s/rad", base: [1, 2, -1, 0, 0, 0, 0, -1], display_units: &[] },
    UnitDefinition { name: "V", base: [1, 2, -3, -1, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "A", base: [0, 0, 0, 1, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "A/s", base: [0, 0, -1, 1, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "Ohm", base: [1, 2, -3, -2, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "H", base: [1, 2, -2, -2, 0, 0, 0, 0], display_units: &[("mH", 1e3)] },
    UnitDefinition { name: "V.s/rad", base: [1, 2, -2, -1, 0, 0, 0, -1], display_units: &[] },
    UnitDefinition { name: "N.m/A", base: [1, 2, -2, -1, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "Pa", base: [1, -1, -2, 0, 0, 0, 0, 0], display_units: &[("bar", 1e-5), ("MPa", 1e-6)] },
    UnitDefinition { name: "Pa/s", base: [1, -1, -3, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "m3", base: [0, 3, 0, 0, 0, 0, 0, 0], display_units: &[("L", 1e3)] },
    UnitDefinition { name: "m3/s", base: [0, 3, -1, 0, 0, 0, 0, 0], display_units: &[("L/min", 6e4)] },
    UnitDefinition { name: "m3/(s.Pa)", base: [-1, 4, 1, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "1/N", base: [-1, -1, 2, 0, 0, 0, 0, 0], display_units: &[] },
    UnitDefinition { name: "rad", base: [0, 0, 0, 0, 0, 0, 0, 1], display_units: &[("deg", DEG_PER_RAD)] },
    UnitDefinition { name: "rad.s", base: [0, 0, 1, 0, 0, 0, 0, 1], display_units: &[] },
    UnitDefinition { name: "rad/s", base: [0, 0, -1, 0, 0, 0, 0, 1], display_units: &[("deg/s", DEG_PER_RAD)] },
    UnitDefinition { name: "rad/s2", base: [0, 0, -2, 0, 0, 0, 0, 1], display_units: &[("deg/s2", DEG_PER_RAD)] },
];
