//! The machine's parameters that both models declare (the platform simulates the machine; the
//! controller's programme forces and voltages need the same stand, legs and drives), each
//! named, described and given its unit once here. A model places each at its own value
//! reference and binds it to its own field.

use super::variables::VariableGroup as V;

/// The legs as bodies' parameters as knowns of a dependency list, in the indices of the
/// model's own `group` module (both models declare them, under the same names).
macro_rules! leg_body_knowns {
    () => {
        &[
            All(group::LEG_CYLINDER_MASS),
            All(group::LEG_ROD_MASS),
            All(group::LEG_CYLINDER_COM),
            All(group::LEG_ROD_COM),
            All(group::LEG_CYLINDER_INERTIA),
            All(group::LEG_ROD_INERTIA),
        ]
    };
}
pub(crate) use leg_body_knowns;

/// The electric drives' law's parameters as knowns, as [`leg_body_knowns`].
macro_rules! drive_law_knowns {
    () => {
        &[
            All(group::MOTOR_R),
            All(group::MOTOR_L),
            All(group::MOTOR_KE),
            All(group::MOTOR_KT),
            All(group::MOTOR_J),
            All(group::MOTOR_D),
            All(group::GEAR_RATIO),
            All(group::SCREW_LEAD),
        ]
    };
}
pub(crate) use drive_law_knowns;

/// `M`, kg.
pub const fn mass(vr: u32) -> V {
    V::parameter("M", &[], vr, Some("kg"), "Mass of the loaded platform (platform plus payload)")
}

/// `J`, kg m².
pub const fn inertia(vr: u32) -> V {
    V::parameter(
        "J",
        &[3],
        vr,
        Some("kg.m2"),
        "Principal central moments of inertia about the body axes e1, e2, e3 (must satisfy the triangle inequality)",
    )
}

/// `g`, m/s².
pub const fn gravity(vr: u32) -> V {
    V::parameter("g", &[], vr, Some("m/s2"), "Gravitational acceleration, acting along -z")
}

/// `B`, m.
pub const fn base_joints(vr: u32) -> V {
    V::parameter("B", &[6, 3], vr, Some("m"), "Base joint B_k (row k: x, y, z) in the inertial frame")
}

/// `A`, m.
pub const fn platform_joints(vr: u32) -> V {
    V::parameter(
        "A",
        &[6, 3],
        vr,
        Some("m"),
        "Platform joint A_k (row k: components along e1, e2, e3) in the body frame, from the centre of mass",
    )
}

/// `lmin`, m.
pub const fn stroke_lower(vr: u32) -> V {
    V::parameter(
        "lmin",
        &[6],
        vr,
        Some("m"),
        "Shortest leg length (lower end stop) of leg k: below it the stop pushes the platform away from the base",
    )
}

/// `lmax`, m.
pub const fn stroke_upper(vr: u32) -> V {
    V::parameter(
        "lmax",
        &[6],
        vr,
        Some("m"),
        "Longest leg length (upper end stop) of leg k: above it the stop pulls the platform towards the base",
    )
}

/// `leg.rodMass`, kg.
pub const fn rod_mass(vr: u32) -> V {
    V::parameter("leg.rodMass", &[], vr, Some("kg"), "Mass m_r of each leg's rod (piston), hinged at A_k")
}

/// `leg.cylinderCoM`, m.
pub const fn cylinder_com(vr: u32) -> V {
    V::parameter(
        "leg.cylinderCoM",
        &[],
        vr,
        Some("m"),
        "Distance d_c of the cylinder's centre of mass from B_k along the leg",
    )
}

/// `leg.rodCoM`, m.
pub const fn rod_com(vr: u32) -> V {
    V::parameter(
        "leg.rodCoM",
        &[],
        vr,
        Some("m"),
        "Distance d_r of the rod's centre of mass from A_k back along the leg",
    )
}

/// `leg.cylinderInertia`, kg m².
pub const fn cylinder_inertia(vr: u32) -> V {
    V::parameter(
        "leg.cylinderInertia",
        &[],
        vr,
        Some("kg.m2"),
        "Transverse moment of inertia J_c of the cylinder about its centre of mass (spin about the leg is ignored)",
    )
}

/// `leg.rodInertia`, kg m².
pub const fn rod_inertia(vr: u32) -> V {
    V::parameter(
        "leg.rodInertia",
        &[],
        vr,
        Some("kg.m2"),
        "Transverse moment of inertia J_r of the rod about its centre of mass",
    )
}

/// `motor.R`, Ohm.
pub const fn motor_resistance(vr: u32) -> V {
    V::parameter("motor.R", &[], vr, Some("Ohm"), "Armature resistance R of each drive's motor")
}

/// `motor.L`, H.
pub const fn motor_inductance(vr: u32) -> V {
    V::parameter("motor.L", &[], vr, Some("H"), "Armature inductance L (L/R is the current's time constant)")
}

/// `motor.ke`, V s/rad.
pub const fn motor_ke(vr: u32) -> V {
    V::parameter("motor.ke", &[], vr, Some("V.s/rad"), "Back-EMF constant k_e: the motor's voltage per shaft rate")
}

/// `motor.kt`, N m/A.
pub const fn motor_kt(vr: u32) -> V {
    V::parameter(
        "motor.kt",
        &[],
        vr,
        Some("N.m/A"),
        "Torque constant k_t: the motor's torque per ampere (= k_e in SI units for an ideal machine)",
    )
}

/// `motor.J`, kg m².
pub const fn motor_inertia(vr: u32) -> V {
    V::parameter(
        "motor.J",
        &[],
        vr,
        Some("kg.m2"),
        "Inertia J_m of the rotor, reducer and screw at the motor shaft: a mass J_m N^2 moving with the leg's length",
    )
}

/// `motor.D`, N m s/rad.
pub const fn motor_damping(vr: u32) -> V {
    V::parameter("motor.D", &[], vr, Some("N.m.s/rad"), "Viscous friction D at the motor shaft (bearings, screw)")
}

/// `gear.ratio`.
pub const fn gear_ratio(vr: u32) -> V {
    V::parameter("gear.ratio", &[], vr, Some("1"), "Reducer ratio i: motor turns per screw turn")
}

/// `screw.lead`, m.
pub const fn screw_lead(vr: u32) -> V {
    V::parameter(
        "screw.lead",
        &[],
        vr,
        Some("m"),
        "Ball screw lead p: leg travel per screw turn (the motor turns N = 2 pi i / p rad per metre of leg)",
    )
}

/// What moves the legs (`drive`): the same codes in both models, the actuators' list's
/// (`crate::physics::actuators`).
pub use crate::physics::actuators::ActuatorKind as Drive;

impl super::declare::IntegerStorage for Drive {
    fn code(&self) -> i32 {
        Drive::code(*self)
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        *self = Drive::from_code(code).ok_or_else(|| {
            let items: Vec<String> = Drive::ALL.iter().map(|k| format!("{} ({})", k.code(), k.name())).collect();
            format!("{code} is none of {}", items.join(", "))
        })?;
        Ok(())
    }
}

/// `hydraulic.bore`, m.
pub const fn hydraulic_bore(vr: u32) -> V {
    V::parameter(
        "hydraulic.bore",
        &[],
        vr,
        Some("m"),
        "Bore D of each hydraulic cylinder: cap-side area A_A = pi D^2/4 (drive = 2)",
    )
}

/// `hydraulic.rod`, m.
pub const fn hydraulic_rod(vr: u32) -> V {
    V::parameter(
        "hydraulic.rod",
        &[],
        vr,
        Some("m"),
        "Rod diameter d of each hydraulic cylinder: rod-side area A_B = pi (D^2 - d^2)/4 (drive = 2)",
    )
}

/// `valve.ratedFlow`, m³/s.
pub const fn valve_rated_flow(vr: u32) -> V {
    V::parameter(
        "valve.ratedFlow",
        &[],
        vr,
        Some("m3/s"),
        "Rated flow Q_N of each servo valve, fully open at the rated pressure drop (flow coefficient K = Q_N / \
         sqrt(dp_N/2))",
    )
}

/// `valve.ratedPressureDrop`, Pa.
pub const fn valve_rated_pressure_drop(vr: u32) -> V {
    V::parameter(
        "valve.ratedPressureDrop",
        &[],
        vr,
        Some("Pa"),
        "Pressure drop dp_N over the valve (both lands) at which it passes its rated flow",
    )
}
