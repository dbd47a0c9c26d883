//! What drives the legs: leg force laws `u_k(t, state)` (the inputs `F`, springs, feedback
//! closures), and the actuators, each one thing ([`Actuator`]): its parameters, its states (a
//! block of the simulation state), its law written once over the number type, its axial force
//! and what it adds to the outputs. The list [`actuators!`](crate::physics::actuators) below
//! names each once (its `drive` code, module and type): the kinds, the active actuator's
//! dispatch and the simulation state's layout follow from it.
//!
//! | actuator | states | inputs |
//! |---|---|---|
//! | [`forces::ForceInputs`] (`drive = 0`) | none | the leg forces `F` |
//! | [`drives::ElectricDrives`] (`drive = 1`) | the armature currents, `work.electric` | the voltages `U` |
//! | [`hydraulics::HydraulicActuators`] (`drive = 2`) | the chambers' pressures, the spools and their rates, `work.hydraulic`, `work.compression` | the valve commands and `pS` |
//!
//! `u_k > 0` pushes the platform away from the base (extension), N.

use crate::physics::body::state::{BodyState, STATE_DIM};
use crate::physics::error::{ParameterError, PhysicsFault};
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::number::{Number, Real};
use crate::physics::stand::LEG_COUNT;

/// Every actuator the legs can have, each named once: its kind (the `drive` parameter's code),
/// its module and its type ([`Actuator`]). The kinds ([`ActuatorKind`]), the active actuator
/// with its parameters ([`ActiveActuator`]), its dispatch (`with_actuator!`) and the blocks of
/// the simulation state ([`layout`], in this order) follow.
macro_rules! actuators {
    ($($kind:ident($field:ident) = $code:literal => $module:ident :: $actuator:ident,)*) => {
        actuators!(@with ($) $($kind($field) = $code => $module :: $actuator,)*);
    };
    (@with ($d:tt) $($kind:ident($field:ident) = $code:literal => $module:ident :: $actuator:ident,)*) => {
        $(pub mod $module;)*

        /// One value per actuator kind, by the kind's name (an FMU's inputs per kind, say).
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct PerActuator<T> {
            $(pub $field: T,)*
        }

        impl<T> PerActuator<T> {
            pub fn get(&self, kind: ActuatorKind) -> &T {
                match kind {
                    $(ActuatorKind::$kind => &self.$field,)*
                }
            }

            pub fn get_mut(&mut self, kind: ActuatorKind) -> &mut T {
                match kind {
                    $(ActuatorKind::$kind => &mut self.$field,)*
                }
            }
        }

        /// Every actuator's parameters (an FMU has them all, whichever is in the legs).
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct Actuators {
            $(pub $field: $module::$actuator,)*
        }

        impl Actuators {
            /// The actuator of kind `kind`, with its parameters.
            pub fn active(&self, kind: ActuatorKind) -> ActiveActuator {
                match kind {
                    $(ActuatorKind::$kind => ActiveActuator::$kind(self.$field),)*
                }
            }
        }

        /// What moves the legs: one of the actuators (the `drive` parameter).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
        pub enum ActuatorKind {
            #[default]
            $($kind,)*
        }

        impl ActuatorKind {
            pub const ALL: [ActuatorKind; 0 $(+ actuators!(@one $kind))*] = [$(ActuatorKind::$kind),*];

            /// The `drive` parameter's code.
            pub fn code(self) -> i32 {
                match self {
                    $(ActuatorKind::$kind => $code,)*
                }
            }

            pub fn from_code(code: i32) -> Option<Self> {
                ActuatorKind::ALL.into_iter().find(|k| k.code() == code)
            }

            /// The kind's place in [`ActuatorKind::ALL`].
            pub fn index(self) -> usize {
                self as usize
            }

            /// What the kind's inputs are, in words, and their unit (for messages).
            pub fn inputs(self) -> (&'static str, &'static str) {
                match self {
                    $(ActuatorKind::$kind => (<$module::$actuator as Actuator>::INPUTS, <$module::$actuator as Actuator>::INPUT_UNIT),)*
                }
            }

            /// What the kind is, in words (the `drive` parameter's items).
            pub fn name(self) -> &'static str {
                match self {
                    $(ActuatorKind::$kind => <$module::$actuator as Actuator>::NAME,)*
                }
            }

            /// Its block of the simulation state.
            pub fn block(self) -> std::ops::Range<usize> {
                match self {
                    $(ActuatorKind::$kind => layout::$kind,)*
                }
            }
        }

        /// The actuator in the legs, with its parameters. Held by value: the simulation copies
        /// it and the step allocates nothing, so the hydraulic legs' parameters make it large.
        #[allow(clippy::large_enum_variant)]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum ActiveActuator {
            $($kind($module::$actuator),)*
        }

        impl ActiveActuator {
            pub fn kind(&self) -> ActuatorKind {
                match self {
                    $(ActiveActuator::$kind(_) => ActuatorKind::$kind,)*
                }
            }

            /// [`Actuator::AT_LEG_RATES`] of the active actuator.
            pub fn at_leg_rates(&self) -> bool {
                match self {
                    $(ActiveActuator::$kind(_) => <$module::$actuator as Actuator>::AT_LEG_RATES,)*
                }
            }

            /// [`Actuator::on_strokes`].
            pub fn on_strokes(self, lower: &[f64; LEG_COUNT], upper: &[f64; LEG_COUNT]) -> Self {
                match self {
                    $(ActiveActuator::$kind(a) => ActiveActuator::$kind(a.on_strokes(lower, upper)),)*
                }
            }

            /// [`Actuator::take_inputs`] from the same kind's parameters in `from`.
            pub fn take_inputs(&mut self, from: &Actuators) {
                match self {
                    $(ActiveActuator::$kind(a) => a.take_inputs(&from.$field),)*
                }
            }
        }

        /// `with_actuator!(active, a => expr)`: `expr` with `a` the active actuator, of its own
        /// type (each arm compiled for it).
        macro_rules! with_actuator {
            ($d active:expr, $d a:ident => $d e:expr) => {
                match $d active {
                    $($crate::physics::actuators::ActiveActuator::$kind($d a) => $d e,)*
                }
            };
        }
        pub(crate) use with_actuator;

        $(impl InState for $module::$actuator {
            const BLOCK: std::ops::Range<usize> = layout::$kind;
        })*

        /// The blocks of the simulation state the actuators' states take, in the list's order
        /// after the body's coordinates and the legs' two integrals (`work.F`,
        /// `work.dissipated`): each actuator's block starts where the last ended.
        pub mod layout {
            #[allow(unused_imports)]
            use super::*;
            /// Where the actuators' blocks start.
            pub const START: usize = crate::physics::body::state::STATE_DIM + 2;
            actuators!(@blocks START; $($kind => $module :: $actuator,)*);
        }
    };
    (@one $kind:ident) => { 1 };
    (@blocks $start:expr; $kind:ident => $module:ident :: $actuator:ident, $($rest:tt)*) => {
        #[allow(non_upper_case_globals)]
        pub const $kind: std::ops::Range<usize> = $start..$start + <super::$module::$actuator as super::Actuator>::STATES;
        actuators!(@blocks $kind.end; $($rest)*);
    };
    (@blocks $end:expr;) => {
        /// Where the last block ends: the length of the simulation state.
        pub const END: usize = $end;
    };
}

actuators! {
    Forces(forces) = 0 => forces::ForceInputs,
    Electric(electric) = 1 => drives::ElectricDrives,
    Hydraulic(hydraulic) = 2 => hydraulics::HydraulicActuators,
}

impl ActiveActuator {
    /// [`Actuator::axial_mass`].
    pub fn axial_mass(&self) -> f64 {
        with_actuator!(self, a => a.axial_mass())
    }

    /// [`Actuator::validate`].
    pub fn validate(&self) -> Result<(), ParameterError> {
        with_actuator!(self, a => Actuator::validate(a))
    }

    /// Its states at the start into its block of the simulation state `y`
    /// ([`Actuator::initial_state`]), the other actuators' blocks zero.
    pub fn initial_state(&self, y: &mut [f64]) {
        if let Some(blocks) = y.get_mut(layout::START..layout::END) {
            blocks.fill(0.0);
        }
        if let Some(x) = y.get_mut(self.kind().block()) {
            with_actuator!(self, a => a.initial_state(x));
        }
    }

    /// Where its active states end in the simulation state ([`Actuator::active_states`]).
    pub fn active_end(&self) -> usize {
        self.kind().block().start + with_actuator!(self, a => a.active_states())
    }

    /// [`Actuator::describe`].
    pub fn describe(&self) -> String {
        with_actuator!(self, a => a.describe())
    }

    /// [`Actuator::check_start`] at the simulation state `y` and the initial leg lengths `l`.
    pub fn check_start(&self, y: &[f64], l: &[f64; LEG_COUNT]) -> Result<(), ParameterError> {
        let x = y.get(self.kind().block()).unwrap_or(&[]);
        with_actuator!(self, a => a.check_start(x, l))
    }
}

/// Where an actuator's block lies in the simulation state ([`layout`], from the list).
pub trait InState {
    const BLOCK: std::ops::Range<usize>;
}

/// An actuator in the legs, one thing: its parameters (the implementing type), its states (a
/// block of the simulation state, [`layout`]), its law (one rate, written once over the number
/// type, which the definition and the steps' fast path both run through a [`BodyRate`]), its
/// axial force on the legs and the energy it stores. A new actuator is a type implementing this
/// in a module of its own and one line in the list above.
pub trait Actuator: Copy + std::fmt::Debug + PartialEq {
    /// What it is, in words (the `drive` parameter's item).
    const NAME: &'static str;
    /// How many states it adds (its block's length).
    const STATES: usize;
    /// Whether its axial force depends on each leg's rate (the electric drives' back EMF and
    /// shaft friction): its law then runs inside the body's evaluation, in the machine's path.
    const AT_LEG_RATES: bool = false;
    /// Whether [`Actuator::check`] checks anything (else the steps skip it).
    const CHECKS: bool = false;
    /// Whether [`Actuator::stable_step`] bounds the fixed-step method's step (else no bound is
    /// asked for).
    const BOUNDED: bool = false;
    /// Whether its path is the one a step's cycle most often takes (the paper's force inputs):
    /// the others are laid out of its way.
    const HOT: bool = false;
    /// What its inputs are, in words, and their unit (the messages of a failed step).
    const INPUTS: &'static str;
    const INPUT_UNIT: &'static str;

    /// The rate of its states `x` into `dx` (its block) and of the body into `dy`, for the
    /// inputs and body of `body`; returns the legs' integrands (`work.F`, `work.dissipated`).
    fn rate<T: Real, B: BodyRate<T>>(&self, body: &B, x: &[T], dy: &mut [T; STATE_DIM], dx: &mut [T]) -> LegPower<T>;

    /// Its axial forces on the legs at body state `state` (legs `legs`), its states `x` and the
    /// inputs `u` (the output `actuatorForce`).
    fn axial_forces<T: Real>(
        &self,
        state: &BodyState<T>,
        legs: &LegGeometry<T>,
        platform_joints: &[nalgebra::Vector3<f64>; LEG_COUNT],
        x: &[T],
        u: &[T; LEG_COUNT],
    ) -> [T; LEG_COUNT];

    /// How many of its states move with its parameters (the leading part of its block; the
    /// rest stay as they are, and the integrators' error norms leave them out).
    fn active_states(&self) -> usize {
        Self::STATES
    }

    /// The energy its states store (in `E`), if any.
    fn stored_energy<T: Real>(&self, _x: &[T]) -> Option<T> {
        None
    }

    /// A mass moving with each leg's length (the drives' rotors), kg: it joins the legs' inertia.
    fn axial_mass(&self) -> f64 {
        0.0
    }

    /// The part of its block whose rate is linear in it with a constant decay rate (1/s),
    /// which the fixed-step method integrates exactly: `(first, count, rate)` within the block.
    fn linear_decay(&self) -> Option<(usize, usize, f64)> {
        None
    }

    /// The longest step the explicit fixed-step method is stable for at its states `x` and the
    /// legs' lengths (computed when asked for: `legs(with_rates)`, the rates too if asked, else
    /// 0) (`inf`: no bound).
    fn stable_step(&self, _x: &[f64], _legs: impl FnOnce(bool) -> LegMotion) -> f64 {
        f64::INFINITY
    }

    /// Whether its states `x` at leg lengths `l` are ones the motion can go on from; `lowest`
    /// takes what the actuator tracks (the hydraulic legs' lowest pressure).
    fn check(&self, _x: &[f64], _l: &[f64; LEG_COUNT], _lowest: &mut f64) -> Result<(), PhysicsFault> {
        Ok(())
    }

    /// Checks its parameters (FMI names in the errors).
    fn validate(&self) -> Result<(), ParameterError>;

    /// Its states at the start (`x`: its block, zeros when given) from its parameters.
    fn initial_state(&self, _x: &mut [f64]) {}

    /// Checks its states at the start `x` against the initial leg lengths `l`.
    fn check_start(&self, _x: &[f64], _l: &[f64; LEG_COUNT]) -> Result<(), ParameterError> {
        Ok(())
    }

    /// The same actuator on legs of strokes `[lower, upper]` (the end stops' `lmin`, `lmax`,
    /// whether the stops act or not): what the hydraulic legs' chambers span.
    fn on_strokes(self, _lower: &[f64; LEG_COUNT], _upper: &[f64; LEG_COUNT]) -> Self {
        self
    }

    /// Takes the inputs held in its parameters (the hydraulic supply pressure) from `from`, the
    /// same actuator as the model's parameters hold it now.
    fn take_inputs(&mut self, _from: &Self) {}

    /// Its parameters in use, for a log (`", electric drives (...)"`; empty for none).
    fn describe(&self) -> String {
        String::new()
    }
}

/// What an actuator's rate evaluates the platform through: the definition (any number type,
/// leg by leg, for Model Exchange and the exact derivatives) or the steps' fast path (the six
/// legs side by side in vector registers), which give the same numbers
/// (`crate::physics::special_form`).
pub trait BodyRate<T: Real> {
    /// The inputs (the leg forces, voltages or valve commands).
    fn inputs(&self) -> [T; LEG_COUNT];
    /// The hydraulic supply's inputs held over a step: the pressure `pS` and `pump.speed`.
    fn supply(&self) -> Supply<T>;
    /// The legs' lengths and rates.
    fn legs(&self) -> ([T; LEG_COUNT], [T; LEG_COUNT]);
    /// The body's rate (into `dy`) under the inputs as axial forces, and the legs' powers.
    fn under_inputs(&self, dy: &mut [T; STATE_DIM]) -> LegPower<T>;
    /// The body's rate under the axial forces `u`, and the legs' powers.
    fn under_forces(&self, u: &[T; LEG_COUNT], dy: &mut [T; STATE_DIM]) -> LegPower<T>;
    /// The body's rate with the electric drives (which the body's form must have) at their
    /// currents, the inputs their voltages: the drives' law at each leg's rate.
    fn driven(&self, currents: &[T; LEG_COUNT], dy: &mut [T; STATE_DIM]) -> DrivenRates<T>;
    /// An actuator's per-leg law at each leg, its `I` inputs given per leg (`inputs[i][k]`):
    /// leg by leg in the definition, the six side by side in the fast path's lanes (the same
    /// bits: [`Number`]'s operations are the scalar ones in each lane).
    #[inline(always)]
    fn per_leg<P: PerLegLaw<I, O>, const I: usize, const O: usize>(
        &self,
        law: &P,
        inputs: &[[T; LEG_COUNT]; I],
    ) -> [[T; LEG_COUNT]; O] {
        let mut out = [[T::zero(); LEG_COUNT]; O];
        for k in 0..LEG_COUNT {
            let mut leg = [T::zero(); I];
            for (value, input) in leg.iter_mut().zip(inputs) {
                *value = input[k];
            }
            for (output, value) in out.iter_mut().zip(law.at(leg)) {
                output[k] = value;
            }
        }
        out
    }
}

/// A law of one leg written once over [`Number`] (`I` inputs to `O` outputs), which
/// [`BodyRate::per_leg`] runs on each leg or on the six side by side.
pub trait PerLegLaw<const I: usize, const O: usize> {
    fn at<N: Number>(&self, inputs: [N; I]) -> [N; O];
}

/// The hydraulic supply's inputs, held over a step: the supply pressure `pS` (Pa; the legs'
/// supply without the power unit) and the power unit's `pump.speed` (1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supply<T = f64> {
    pub pressure: T,
    pub pump_speed: T,
}

/// The legs' lengths `l_k` (m) and rates `ldot_k` (m/s) at a state.
#[derive(Clone, Copy, Debug)]
pub struct LegMotion {
    pub lengths: [f64; LEG_COUNT],
    pub rates: [f64; LEG_COUNT],
}

/// The powers of a right-hand-side evaluation (or their changes, from
/// `SpecialForm::derivative_tangent`): the integrands of `work.F` and `work.dissipated`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LegPower<T = f64> {
    /// Power of the actuator forces, `sum_k F_k ldot_k = F.v + L.omega`, W.
    pub actuator: T,
    /// Power taken by the end stops' and joint limits' damping and by friction, W (>= 0).
    pub dissipation: T,
}

/// What the body's rate with electric drives gives besides the body's rates: the legs' powers
/// (of the given forces: 0, the drives' work is electric; the dissipation without the drives'
/// losses), the currents' rates and the sums of the drives' powers.
#[derive(Clone, Copy, Debug, Default)]
pub struct DrivenRates<T = f64> {
    pub power: LegPower<T>,
    /// `I_k'`, A/s.
    pub current_rate: [T; LEG_COUNT],
    /// `sum U_k I_k`, W.
    pub electric_power: T,
    /// The drives' losses, W.
    pub drive_dissipation: T,
}

/// Axial leg forces as a function of time and state.
pub trait LegForceLaw {
    fn leg_forces(&self, t: f64, state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT];

    /// Whether the forces depend on the state. If not, the right-hand side skips building
    /// the [`LegGeometry`] (the fast path of every co-simulation step, whose forces are
    /// inputs) and calls [`LegForceLaw::leg_forces_at`].
    fn depends_on_state(&self) -> bool {
        true
    }

    /// The forces of a law that does not depend on the state.
    fn leg_forces_at(&self, _t: f64) -> [f64; LEG_COUNT] {
        [0.0; LEG_COUNT]
    }
}

/// Forces held over a communication step as a first-order polynomial in time:
/// `u_k(t) = value_k + slope_k (t - t0)`. With zero slopes this is the zero-order hold a
/// co-simulation master implies; with slopes from `fmi2SetRealInputDerivatives` it is the
/// first-order input interpolation of FMI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldForces {
    pub value: [f64; LEG_COUNT],
    pub slope: [f64; LEG_COUNT],
    pub t0: f64,
}

impl HeldForces {
    pub fn constant(value: [f64; LEG_COUNT]) -> Self {
        HeldForces { value, slope: [0.0; LEG_COUNT], t0: 0.0 }
    }
}

impl LegForceLaw for HeldForces {
    #[inline(always)]
    fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
        self.leg_forces_at(t)
    }

    fn depends_on_state(&self) -> bool {
        false
    }

    #[inline(always)]
    fn leg_forces_at(&self, t: f64) -> [f64; LEG_COUNT] {
        let dt = t - self.t0;
        let mut u = self.value;
        for k in 0..LEG_COUNT {
            u[k] += self.slope[k] * dt;
        }
        u
    }
}

/// Legs replaced by linear springs: `u_k = -c (l_k - L_k0)`. A conservative system (the
/// textbook's energy check, docs/model.md §7): potential `c/2 sum_k (l_k - L_k0)²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringLegs {
    /// Spring stiffness `c`, N/m.
    pub stiffness: f64,
    /// Unstretched lengths `L_k0`, m.
    pub rest_length: [f64; LEG_COUNT],
}

impl SpringLegs {
    /// Potential energy stored in the springs, J.
    pub fn potential_energy(&self, legs: &LegGeometry) -> f64 {
        (0..LEG_COUNT).map(|k| 0.5 * self.stiffness * (legs.length[k] - self.rest_length[k]).powi(2)).sum()
    }
}

impl LegForceLaw for SpringLegs {
    fn leg_forces(&self, _t: f64, _state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT] {
        let mut u = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            u[k] = -self.stiffness * (legs.length[k] - self.rest_length[k]);
        }
        u
    }
}

/// Any closure `|t, state, legs| -> [u_k]` is a force law (tests, feedback experiments).
impl<F> LegForceLaw for F
where
    F: Fn(f64, &BodyState, &LegGeometry) -> [f64; LEG_COUNT],
{
    fn leg_forces(&self, t: f64, state: &BodyState, legs: &LegGeometry) -> [f64; LEG_COUNT] {
        self(t, state, legs)
    }
}

#[cfg(test)]
mod tests {
    use super::ActuatorKind;

    /// The `drive` codes are the list's places, 0 to n - 1: the platform declares `drive`'s
    /// range as `0..=ActuatorKind::ALL.len() - 1`.
    #[test]
    fn the_codes_are_the_lists_places() {
        for (place, kind) in ActuatorKind::ALL.into_iter().enumerate() {
            assert_eq!(kind.code(), place as i32, "{}", kind.name());
            assert_eq!(ActuatorKind::from_code(place as i32), Some(kind));
        }
    }
}
