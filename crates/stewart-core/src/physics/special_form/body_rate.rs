//! The two ways an actuator's rate ([`crate::physics::actuators::Actuator::rate`]) evaluates
//! the body ([`BodyRate`]): the definition in any number type (Model Exchange, the exact
//! derivatives), and the steps' fast path with the six legs side by side in vector registers.
//! The same numbers: bit for bit for the paper's legs, to round-off for the machine's
//! (`super::fast_path`).

use std::marker::PhantomData;

use super::{Actuation, SpecialForm, sum_over_legs};
use crate::physics::actuators::{BodyRate, DrivenRates, HeldForces, LegForceLaw, LegPower, PerLegLaw, Supply};
use crate::physics::body::state::{BodyState, STATE_DIM, StateVector};
use crate::physics::legs::geometry::LegGeometry;
use crate::physics::legs::per_leg::{Lanes, PerLeg};
use crate::physics::number::Real;
use crate::physics::stand::LEG_COUNT;

/// The definition ([`SpecialForm::rate`], [`SpecialForm::rate_driven`]) at the body
/// coordinates `body` for the inputs `inputs` and the hydraulic supply pressure `supply`, in
/// any number type.
pub struct Definition<'a, T: Real> {
    pub form: &'a SpecialForm,
    pub body: &'a [T; STATE_DIM],
    pub inputs: &'a [T; LEG_COUNT],
    pub supply: Supply<T>,
}

impl<T: Real> BodyRate<T> for Definition<'_, T> {
    fn inputs(&self) -> [T; LEG_COUNT] {
        *self.inputs
    }

    fn supply(&self) -> Supply<T> {
        self.supply
    }

    fn legs(&self) -> ([T; LEG_COUNT], [T; LEG_COUNT]) {
        let state = BodyState::from_vector(self.body);
        let legs = LegGeometry::new(&self.form.stand, &state);
        (legs.length, legs.length_rates(&self.form.stand, &state))
    }

    fn under_inputs(&self, dy: &mut [T; STATE_DIM]) -> LegPower<T> {
        self.under_forces(self.inputs, dy)
    }

    fn under_forces(&self, u: &[T; LEG_COUNT], dy: &mut [T; STATE_DIM]) -> LegPower<T> {
        let (rate, power) = self.form.rate(self.body, u);
        *dy = rate;
        power
    }

    fn driven(&self, currents: &[T; LEG_COUNT], dy: &mut [T; STATE_DIM]) -> DrivenRates<T> {
        let (rate, power, drives) = self.form.rate_driven(self.body, currents, self.inputs);
        *dy = rate;
        DrivenRates {
            power,
            current_rate: drives.map(|d| d.current_rate),
            electric_power: sum_over_legs(&drives.map(|d| d.electric_power)),
            drive_dissipation: sum_over_legs(&drives.map(|d| d.dissipation)),
        }
    }
}

/// The steps' fast path ([`SpecialForm::derivative`] and the machine's, in lanes `V`) at
/// time `t` and body coordinates `body`, the inputs from the law `law`.
pub struct FastPath<'a, L: ?Sized, V: Lanes> {
    pub form: &'a SpecialForm,
    pub t: f64,
    pub body: &'a StateVector,
    pub law: &'a L,
    pub lanes: PhantomData<V>,
}

impl<L: LegForceLaw + ?Sized, V: Lanes> BodyRate<f64> for FastPath<'_, L, V> {
    #[inline(always)]
    fn inputs(&self) -> [f64; LEG_COUNT] {
        if self.law.depends_on_state() {
            let state = BodyState::from_vector(self.body);
            self.law.leg_forces(self.t, &state, &LegGeometry::new(&self.form.stand, &state))
        } else {
            self.law.leg_forces_at(self.t)
        }
    }

    #[inline(always)]
    fn supply(&self) -> Supply {
        self.form.supply()
    }

    /// In the checks' lanes of `V` (`JointArrays::kinematics_in`): the definition's bits.
    #[inline(always)]
    fn legs(&self) -> ([f64; LEG_COUNT], [f64; LEG_COUNT]) {
        let state = BodyState::from_vector(self.body);
        let legs = self.form.joints.kinematics_in::<V>(&state);
        let l_dot = self.form.joints.length_rates_in::<V>(&state, &legs);
        (legs.lengths(), l_dot)
    }

    #[inline(always)]
    fn under_inputs(&self, dy: &mut StateVector) -> LegPower {
        self.form.derivative_in::<L, V>(self.t, self.body, self.law, dy)
    }

    #[inline(always)]
    fn under_forces(&self, u: &[f64; LEG_COUNT], dy: &mut StateVector) -> LegPower {
        self.form.derivative_in::<HeldForces, V>(self.t, self.body, &HeldForces::constant(*u), dy)
    }

    #[inline(always)]
    fn driven(&self, currents: &[f64; LEG_COUNT], dy: &mut StateVector) -> DrivenRates {
        let voltages = self.inputs();
        self.form.derivative_machine_of::<V>(self.body, Actuation::Drives { currents, voltages: &voltages }, dy)
    }

    /// The six legs side by side in `V`'s registers.
    #[inline(always)]
    fn per_leg<P: PerLegLaw<I, O>, const I: usize, const O: usize>(
        &self,
        law: &P,
        inputs: &[[f64; LEG_COUNT]; I],
    ) -> [[f64; LEG_COUNT]; O] {
        let mut lanes = [PerLeg::<V>::splat(0.0); I];
        for (lane, input) in lanes.iter_mut().zip(inputs) {
            *lane = PerLeg::new(input);
        }
        let mut out = [[0.0; LEG_COUNT]; O];
        for (output, value) in out.iter_mut().zip(law.at(lanes)) {
            *output = value.to_array();
        }
        out
    }
}
