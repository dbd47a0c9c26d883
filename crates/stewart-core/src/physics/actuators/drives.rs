//! Electric drives (docs/model.md §9; the textbook's pointing drive, section 4.1.7, eq.
//! 4.137): each leg is a DC motor turning a ball screw through a reducer, a rigid
//! transmission. With the motor shaft rate `omega = N l'`, `N = 2 pi i / p` (rad/m; `i` motor
//! turns per screw turn, `p` the screw's lead):
//!
//! ```text
//! L I' = U - R I - k_e omega           armature circuit
//! u    = N (k_t I - D omega)           axial force on the leg (replaces F)
//! T   += 1/2 J_m omega^2               the rotor's inertia, reflected as J_m N^2 along the leg
//! ```
//!
//! Energy: the circuit stores `1/2 L I^2` and takes `U I` from the supply; `R I^2` and
//! `D omega^2` are lost, and for `k_t != k_e` the conversion mismatch `(k_e - k_t) omega I`
//! is counted as lost too, so that `E(t) - E(0) = work.F + work.electric - work.dissipated`
//! holds whatever the constants (it is zero for an ideal machine, `k_t = k_e` in SI units).
//!
//! The circuit is fast: `L / R` is a millisecond or less, and with the rotor and the load it
//! forms the drive's electromechanical mode. The current's equation is linear with the
//! constant rate `-R/L`, which the fixed-step method integrates exactly
//! (`crate::integration::LinearDecay`).

use super::{Actuator, BodyRate, LegPower};
use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::error::ParameterError;
use crate::physics::legs::geometry::{LegGeometry, joint_rate};
use crate::physics::number::{Number, Real};
use crate::physics::stand::{LEG_COUNT, check_finite};

/// Default armature resistance, Ohm: a 7.5 kW, 300 V servo motor (25 A continuous); it holds
/// the default stand at 18.8 A and 7.5 V per leg.
pub const DEFAULT_RESISTANCE: f64 = 0.4;
/// Default armature inductance, H: an electrical time constant `L / R` of 1 ms.
pub const DEFAULT_INDUCTANCE: f64 = 0.4e-3;
/// Default back-EMF constant, V s/rad (105 V per 1000 rpm): 300 V at 2,865 rpm, the motor's
/// rated speed at its rated voltage.
pub const DEFAULT_KE: f64 = 1.0;
/// Default torque constant, N m/A: equal to `k_e` in SI units (an ideal machine).
pub const DEFAULT_KT: f64 = 1.0;
/// Default rotor and screw inertia at the motor shaft, kg m²: a rotor of 1.2e-3 and a steel
/// ball screw of 32 mm by 1 m (0.8e-3); reflected along the leg, `J N²` (docs/model.md §9).
pub const DEFAULT_ROTOR_INERTIA: f64 = 2.0e-3;
/// Default viscous friction at the motor shaft, N m s/rad (bearings and screw): `D N²` along
/// the leg.
pub const DEFAULT_DAMPING: f64 = 2.0e-3;
/// Default reducer ratio `i`, motor turns per screw turn: a direct drive (or a 1:1 belt).
pub const DEFAULT_GEAR_RATIO: f64 = 1.0;
/// Default screw lead `p`, m: 20 mm per turn. With `i = 1`, `N = 2 pi / p`: the motor turns
/// well within its rated speed on the default heave programme (docs/model.md §9).
pub const DEFAULT_SCREW_LEAD: f64 = 0.02;

/// The drives' parameters (`motor.*`, `gear.ratio`, `screw.lead`), the same for all six legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElectricDrives {
    /// `R`, Ohm.
    pub resistance: f64,
    /// `L`, H.
    pub inductance: f64,
    /// `k_e`, V s/rad.
    pub ke: f64,
    /// `k_t`, N m/A.
    pub kt: f64,
    /// `J_m`, kg m², at the motor shaft.
    pub rotor_inertia: f64,
    /// `D`, N m s/rad, at the motor shaft.
    pub damping: f64,
    /// `i`, motor turns per screw turn.
    pub gear_ratio: f64,
    /// `p`, m per screw turn.
    pub screw_lead: f64,
    /// `I0`, A: the armature currents at the start.
    pub initial_currents: [f64; LEG_COUNT],
}

impl Default for ElectricDrives {
    fn default() -> Self {
        ElectricDrives {
            resistance: DEFAULT_RESISTANCE,
            inductance: DEFAULT_INDUCTANCE,
            ke: DEFAULT_KE,
            kt: DEFAULT_KT,
            rotor_inertia: DEFAULT_ROTOR_INERTIA,
            damping: DEFAULT_DAMPING,
            gear_ratio: DEFAULT_GEAR_RATIO,
            screw_lead: DEFAULT_SCREW_LEAD,
            initial_currents: [0.0; LEG_COUNT],
        }
    }
}

/// One drive's contribution to a right-hand side.
#[derive(Clone, Copy, Debug)]
pub struct DriveRate<T> {
    /// `u`, N: the axial force on the leg.
    pub force: T,
    /// `I'`, A/s.
    pub current_rate: T,
    /// `U I`, W: taken from the supply.
    pub electric_power: T,
    /// `R I^2 + D omega^2 + (k_e - k_t) omega I`, W: lost.
    pub dissipation: T,
}

impl<T: Real> DriveRate<T> {
    pub fn zero() -> Self {
        DriveRate { force: T::zero(), current_rate: T::zero(), electric_power: T::zero(), dissipation: T::zero() }
    }
}

impl ElectricDrives {
    /// `N = 2 pi i / p`, rad/m: the motor's rate per unit leg rate.
    pub fn transmission(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.gear_ratio / self.screw_lead
    }

    /// `J_m N²`, kg: the rotor's inertia as a mass moving with the leg's length.
    pub fn reflected_mass(&self) -> f64 {
        let n = self.transmission();
        self.rotor_inertia * n * n
    }

    /// `R / L`, 1/s: the rate at which the current settles.
    pub fn current_decay_rate(&self) -> f64 {
        self.resistance / self.inductance
    }

    /// The axial force, the current's rate and the powers of a drive at voltage `u`, current
    /// `i` and leg rate `l_dot`: the drive law, for one leg (`f64`, `Dual`) or six side by
    /// side (the step's fast path).
    #[inline(always)]
    pub fn rate<T: Number>(&self, voltage: T, current: T, l_dot: T) -> DriveRate<T> {
        let n = self.transmission();
        let omega = l_dot * n;
        DriveRate {
            force: (current * self.kt - omega * self.damping) * n,
            current_rate: (voltage - current * self.resistance - omega * self.ke) / self.inductance,
            electric_power: voltage * current,
            dissipation: current * current * self.resistance
                + omega * omega * self.damping
                + omega * current * (self.ke - self.kt),
        }
    }

    /// `1/2 L sum I_k²`, J: the magnetic energy of the six circuits.
    pub fn magnetic_energy<T: Real>(&self, currents: &[T; LEG_COUNT]) -> T {
        currents.iter().fold(T::zero(), |sum, &i| sum + i * i) * (0.5 * self.inductance)
    }

    /// The drive's static model: the current and voltage that deliver the axial force `force`
    /// at the leg rate `l_dot` in a steady state, neglecting the shaft's friction
    /// (`I = u / (N k_t)`, `U = R I + k_e N l'`: docs/model.md §9).
    pub fn static_current_and_voltage(&self, force: f64, l_dot: f64) -> (f64, f64) {
        let n = self.transmission();
        let current = force / (n * self.kt);
        (current, current * self.resistance + self.ke * n * l_dot)
    }

    /// Checks the parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for (name, value, positive) in [
            ("motor.R", self.resistance, true),
            ("motor.L", self.inductance, true),
            ("motor.ke", self.ke, false),
            ("motor.kt", self.kt, true),
            ("motor.J", self.rotor_inertia, false),
            ("motor.D", self.damping, false),
            ("gear.ratio", self.gear_ratio, true),
            ("screw.lead", self.screw_lead, true),
        ] {
            check_finite(name, value)?;
            if positive && !(value > 0.0) {
                return Err(ParameterError::new(name, format!("must be > 0, got {value:e}")));
            }
            if value < 0.0 {
                return Err(ParameterError::new(name, format!("must be >= 0, got {value:e}")));
            }
        }
        let n = self.transmission();
        if !(n.is_finite() && self.reflected_mass().is_finite() && self.current_decay_rate().is_finite()) {
            return Err(ParameterError::new(
                "screw.lead",
                format!(
                    "the transmission 2 pi gear.ratio / screw.lead = {n:e} rad/m (reflected rotor mass {:e} kg, R/L = \
                     {:e} 1/s) is not a finite number",
                    self.reflected_mass(),
                    self.current_decay_rate()
                ),
            ));
        }
        Ok(())
    }
}

/// The drives' states: the six armature currents, then `work.electric`.
impl Actuator for ElectricDrives {
    const NAME: &'static str = "electric drives";
    const STATES: usize = LEG_COUNT + 1;
    const AT_LEG_RATES: bool = true;
    const INPUTS: &'static str = "voltages";
    const INPUT_UNIT: &'static str = "V";

    /// The body with the drive law at each leg's rate; the currents' rates and the electric
    /// power; the drives' losses join the dissipation (their work is electric: `work.F` stays
    /// 0).
    #[inline(always)]
    fn rate<T: Real, B: BodyRate<T>>(&self, body: &B, x: &[T], dy: &mut [T; STATE_DIM], dx: &mut [T]) -> LegPower<T> {
        let (Some(currents), Some((rates, [electric]))) =
            (x.first_chunk::<LEG_COUNT>(), dx.split_first_chunk_mut::<LEG_COUNT>())
        else {
            return LegPower { actuator: T::zero(), dissipation: T::zero() };
        };
        let r = body.driven(currents, dy);
        (*rates, *electric) = (r.current_rate, r.electric_power);
        LegPower { actuator: T::zero(), dissipation: r.power.dissipation + r.drive_dissipation }
    }

    /// Each drive's force at its current, the voltage `u_k` and the leg's rate
    /// `l_k' = (a_k - B_k) . a_k' / l_k` (0 for a collapsed leg, which carries nothing).
    fn axial_forces<T: Real>(
        &self,
        state: &BodyState<T>,
        legs: &LegGeometry<T>,
        platform_joints: &[nalgebra::Vector3<f64>; LEG_COUNT],
        x: &[T],
        u: &[T; LEG_COUNT],
    ) -> [T; LEG_COUNT] {
        std::array::from_fn(|k| {
            let l = legs.length[k];
            let l_dot = if l > T::zero() { joint_rate(state, &platform_joints[k], &legs.leg[k]).0 / l } else { T::zero() };
            self.rate(u[k], x.get(k).copied().unwrap_or(T::zero()), l_dot).force
        })
    }

    /// `1/2 L sum I_k²`.
    fn stored_energy<T: Real>(&self, x: &[T]) -> Option<T> {
        Some(self.magnetic_energy(&std::array::from_fn(|k| x.get(k).copied().unwrap_or(T::zero()))))
    }

    fn axial_mass(&self) -> f64 {
        self.reflected_mass()
    }

    /// The currents decay at `R / L`.
    fn linear_decay(&self) -> Option<(usize, usize, f64)> {
        Some((0, LEG_COUNT, self.current_decay_rate()))
    }

    fn validate(&self) -> Result<(), ParameterError> {
        ElectricDrives::validate(self)?;
        for (k, &i) in self.initial_currents.iter().enumerate() {
            check_finite(&format!("I0[{}]", k + 1), i)?;
        }
        Ok(())
    }

    fn initial_state(&self, x: &mut [f64]) {
        if let Some(currents) = x.first_chunk_mut::<LEG_COUNT>() {
            *currents = self.initial_currents;
        }
    }

    fn describe(&self) -> String {
        format!(
            ", electric drives (voltage inputs U; N = {:.4} rad/m, rotor {:.1} kg along each leg, L/R = {:e} s, \
             initial currents {:?} A)",
            self.transmission(),
            self.reflected_mass(),
            1.0 / self.current_decay_rate(),
            self.initial_currents
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The powers add up: `d(1/2 L I²)/dt + u l' = U I - dissipation`, the drive's energy
    /// balance, whatever `k_t` and `k_e`.
    #[test]
    fn the_drives_power_balance_closes() {
        for kt in [1.0, 0.8] {
            let d = ElectricDrives { kt, ..ElectricDrives::default() };
            let (u, i, l_dot) = (120.0, 17.0, -0.3);
            let r = d.rate(u, i, l_dot);
            let magnetic_rate = d.inductance * i * r.current_rate;
            let residual = magnetic_rate + r.force * l_dot - (r.electric_power - r.dissipation);
            // The rotor's kinetic energy is the legs' (reflected mass): not part of this balance.
            assert!(residual.abs() < 1e-10 * r.electric_power.abs(), "kt {kt}: residual {residual:e} W");
        }
    }

    /// The static model holds the force: at its current and voltage the current does not change
    /// and the force is the one asked for, up to the shaft friction.
    #[test]
    fn the_static_model_is_a_steady_state() {
        let d = ElectricDrives { damping: 0.0, ..ElectricDrives::default() };
        let (i, u) = d.static_current_and_voltage(5900.715, 0.2);
        let r = d.rate(u, i, 0.2);
        assert!(r.current_rate.abs() < 1e-9, "{}", r.current_rate);
        assert!((r.force - 5900.715).abs() < 1e-9, "{}", r.force);
        assert!((i - 5900.715 / (2.0 * std::f64::consts::PI / 0.02)).abs() < 1e-12);
    }
}
