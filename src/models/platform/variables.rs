//! The `StewartPlatform` variables (SPEC §3). Names, units and meanings are part of the
//! contract with hosts and tests: keep them.

use crate::models::variables::Causality::*;
use crate::models::variables::Dependency::{All, SameIndex};
use crate::models::variables::Initial::{Calculated, Exact};
use crate::models::variables::Variability::{Continuous, Fixed};
use crate::models::variables::VariableType::{Integer, Real};
use crate::models::variables::{Dependency, VariableGroup};

/// Indices into [`GROUPS`], matched on by the model.
pub mod group {
    pub const TIME: usize = 0;
    pub const F: usize = 1;
    pub const M: usize = 2;
    pub const J: usize = 3;
    pub const G: usize = 4;
    pub const B: usize = 5;
    pub const A: usize = 6;
    pub const R0: usize = 7;
    pub const ANGLES0: usize = 8;
    pub const V0: usize = 9;
    pub const W0: usize = 10;
    pub const METHOD: usize = 11;
    pub const REL_TOL: usize = 12;
    pub const ABS_TOL: usize = 13;
    pub const MAX_STEP: usize = 14;
    pub const FIXED_STEP: usize = 15;
    pub const STABILISATION: usize = 16;
    pub const R: usize = 17;
    pub const V: usize = 18;
    pub const ROT: usize = 19;
    pub const ANGLES: usize = 20;
    pub const W: usize = 21;
    pub const L: usize = 22;
    pub const LDOT: usize = 23;
    pub const E: usize = 24;
    pub const CONSTRAINT_ERROR: usize = 25;
}

const GEOMETRY: &[Dependency] = &[All("A"), All("B"), All("r0"), All("angles0")];
const NONE: &[Dependency] = &[];

macro_rules! param {
    ($name:expr, $shape:expr, $vr:expr, $unit:expr, $display:expr, $desc:expr) => {
        VariableGroup {
            name: $name,
            shape: $shape,
            first_vr: $vr,
            var_type: Real,
            causality: Parameter,
            variability: Fixed,
            initial: Some(Exact),
            unit: $unit,
            display_unit: $display,
            description: $desc,
            output_dependencies: NONE,
            initial_dependencies: NONE,
            range: None,
        }
    };
}

macro_rules! output {
    ($name:expr, $shape:expr, $vr:expr, $unit:expr, $display:expr, $desc:expr, $init:expr) => {
        VariableGroup {
            name: $name,
            shape: $shape,
            first_vr: $vr,
            var_type: Real,
            causality: Output,
            variability: Continuous,
            initial: Some(Calculated),
            unit: $unit,
            display_unit: $display,
            description: $desc,
            output_dependencies: NONE,
            initial_dependencies: $init,
            range: None,
        }
    };
}

pub static GROUPS: &[VariableGroup] = &[
    VariableGroup {
        name: "time",
        shape: &[],
        first_vr: 0,
        var_type: Real,
        causality: Independent,
        variability: Continuous,
        initial: None,
        unit: Some("s"),
        display_unit: None,
        description: "Simulation time",
        output_dependencies: NONE,
        initial_dependencies: NONE,
        range: None,
    },
    VariableGroup {
        name: "F",
        shape: &[6],
        first_vr: 1,
        var_type: Real,
        causality: Input,
        variability: Continuous,
        initial: None,
        unit: Some("N"),
        display_unit: None,
        description: "Axial leg force u_k acting on the platform at A_k along the leg (positive pushes the platform away \
                      from the base). Held over each communication step, or interpolated to first order when \
                      fmi2SetRealInputDerivatives gave its derivative",
        output_dependencies: NONE,
        initial_dependencies: NONE,
        range: None,
    },
    param!("M", &[], 10, Some("kg"), None, "Mass of the loaded platform (platform plus payload)"),
    param!(
        "J",
        &[3],
        11,
        Some("kg.m2"),
        None,
        "Principal central moments of inertia about the body axes e1, e2, e3 (must satisfy the triangle inequality)"
    ),
    param!("g", &[], 14, Some("m/s2"), None, "Gravitational acceleration, acting along -z"),
    param!("B", &[6, 3], 20, Some("m"), None, "Base joint B_k (row k: x, y, z) in the inertial frame"),
    param!(
        "A",
        &[6, 3],
        40,
        Some("m"),
        None,
        "Platform joint A_k (row k: components along e1, e2, e3) in the body frame, from the centre of mass"
    ),
    param!("r0", &[3], 60, Some("m"), None, "Initial position of the centre of mass"),
    param!("angles0", &[3], 63, Some("rad"), Some("deg"), "Initial roll, pitch, yaw (1-2-3 sequence, R = Rx Ry Rz)"),
    param!("v0", &[3], 66, Some("m/s"), None, "Initial velocity of the centre of mass"),
    param!("w0", &[3], 69, Some("rad/s"), None, "Initial angular velocity, body components"),
    VariableGroup {
        name: "solver.method",
        shape: &[],
        first_vr: 80,
        var_type: Integer,
        causality: Parameter,
        variability: Fixed,
        initial: Some(Exact),
        unit: None,
        display_unit: None,
        description: "Integrator: 1 = Dormand-Prince 5(4), adaptive with error control (solver.relTol, solver.absTol, \
                      solver.maxStep); 2 = classical Runge-Kutta 4 with a fixed step (solver.fixedStep), a fixed cost \
                      per communication step for real time",
        output_dependencies: NONE,
        initial_dependencies: NONE,
        range: Some((1.0, 2.0)),
    },
    param!(
        "solver.relTol",
        &[],
        81,
        Some("1"),
        None,
        "Relative tolerance of the adaptive integrator's local error (replaced by the tolerance of \
         fmi2SetupExperiment when the importer defines one)"
    ),
    param!(
        "solver.absTol",
        &[],
        82,
        Some("1"),
        None,
        "Absolute tolerance of the adaptive integrator's local error, in the units of each state component \
         (m, m/s, unit-vector components and their rates)"
    ),
    param!(
        "solver.maxStep",
        &[],
        83,
        Some("s"),
        None,
        "Largest internal step of the adaptive integrator; 0 = limited only by the communication step"
    ),
    param!(
        "solver.fixedStep",
        &[],
        84,
        Some("s"),
        None,
        "Internal step bound of RungeKutta4: each communication step is split into the fewest equal steps not \
         longer than this; 0 = one step per communication step"
    ),
    VariableGroup {
        name: "solver.stabilisation",
        shape: &[],
        first_vr: 85,
        var_type: Integer,
        causality: Parameter,
        variability: Fixed,
        initial: Some(Exact),
        unit: None,
        display_unit: None,
        description: "Constraint stabilisation: 2 = project onto the constraints e_a.e_b = delta_ab (orthonormal frame, \
                      rigid-rotation velocities) after every internal step; 1 = none, the residual drifts (for \
                      demonstration)",
        output_dependencies: NONE,
        initial_dependencies: NONE,
        range: Some((1.0, 2.0)),
    },
    output!("r", &[3], 100, Some("m"), None, "Centre of mass S, inertial frame", &[SameIndex("r0")]),
    output!("v", &[3], 103, Some("m/s"), None, "Velocity of the centre of mass", &[SameIndex("v0")]),
    output!(
        "R",
        &[3, 3],
        106,
        Some("1"),
        None,
        "Rotation matrix body -> inertial: R[a,b] is component a of the body axis e_b",
        &[All("angles0")]
    ),
    output!(
        "angles",
        &[3],
        115,
        Some("rad"),
        Some("deg"),
        "Roll, pitch, yaw (1-2-3 sequence, R = Rx Ry Rz)",
        &[All("angles0")]
    ),
    output!("w", &[3], 118, Some("rad/s"), None, "Angular velocity, body components", &[SameIndex("w0")]),
    output!("l", &[6], 121, Some("m"), None, "Leg length l_k = |a_k - B_k|", GEOMETRY),
    output!(
        "ldot",
        &[6],
        127,
        Some("m/s"),
        None,
        "Leg length rate dl_k/dt",
        &[All("A"), All("B"), All("r0"), All("angles0"), All("v0"), All("w0")]
    ),
    output!(
        "E",
        &[],
        133,
        Some("J"),
        None,
        "Kinetic plus gravitational potential energy M v^2/2 + w.J w/2 + M g z",
        &[All("M"), All("J"), All("g"), All("r0"), All("v0"), All("w0")]
    ),
    output!(
        "constraintError",
        &[],
        134,
        Some("1"),
        None,
        "Constraint residual max over a, b of |e_a.e_b - delta_ab|",
        &[All("angles0")]
    ),
];
